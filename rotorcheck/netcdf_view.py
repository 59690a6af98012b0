"""The netCDF-4 view of rotorcheck's HDF5 files (xarray ``engine="h5netcdf"``): dimension scales that name
every axis of a dataset, coordinate variables that label an axis (channel names, frequencies) and
``units`` attributes. Only additions: the datasets a file's contract names keep their names, places and
bytes, and rotorcheck's readers ignore the labels (files without them read as before).

netCDF-4 conventions used: an HDF5 dimension scale is a netCDF dimension named after the dataset; a scale
whose ``NAME`` starts with :data:`NOT_A_VARIABLE` is a dimension without a variable (an empty float32
dataset, as netCDF-C writes it), any other scale is a coordinate variable. h5netcdf looks a dimension up
in the dataset's own group first, then in its parents.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import h5py
import numpy as np

#: netCDF-4's ``NAME`` of a dimension scale that is not a variable (followed by the length, 10 wide)
NOT_A_VARIABLE = "This is a netCDF dimension but not a netCDF variable."


class Dimensions:
    """The dimension scales of one HDF5 group, each made on first use and then shared by name. A name asked
    for with another length, or labels of another length, gets the length appended (``pattern_2``), so one
    group never holds two lengths under one name."""

    def __init__(self, group: h5py.Group) -> None:
        self.group = group
        self.scales: dict[str, h5py.Dataset] = {}

    def _new(self, name: str, data: np.ndarray | None, size: int) -> h5py.Dataset:
        # attribute creation order tracked: a newer object header, so REFERENCE_LIST (one entry per attached
        # dataset) may outgrow the 64 KiB of a compact attribute when a scale labels many datasets
        if data is None:
            ds = self.group.create_dataset(name, shape=(size,), dtype=">f4", track_times=False, track_order=True)
            ds.make_scale(f"{NOT_A_VARIABLE}{size:10d}")
        else:
            ds = self.group.create_dataset(name, data=data, track_times=False, track_order=True)
            ds.make_scale(name)
        self.scales[name] = ds
        return ds

    def plain(self, name: str, size: int, suffix: bool = False) -> h5py.Dataset:
        """A dimension without a variable (no labels); ``suffix``: always named ``<name>_<size>``."""
        key = f"{name}_{size}" if suffix else name
        have = self.scales.get(key)
        if have is not None and have.shape == (size,):
            return have
        if have is not None:
            key = f"{name}_{size}"
            if key in self.scales:
                return self.scales[key]
        return self._new(key, None, size)

    def labels(self, name: str, values: Sequence[str], attrs: Mapping[str, str] | None = None) -> h5py.Dataset:
        """A coordinate variable ``name`` holding the text ``values`` (UTF-8), with ``attrs``."""
        have = self.scales.get(name)
        if have is not None and have.shape == (len(values),):
            return have
        key = name if have is None else f"{name}_{len(values)}"
        if key in self.scales:
            return self.scales[key]
        ds = self._new(key, np.asarray(list(values), dtype=h5py.string_dtype("utf-8")), len(values))
        for k, v in (attrs or {}).items():
            ds.attrs[k] = v
        return ds

    def coordinate(self, ds: h5py.Dataset, units: str) -> h5py.Dataset:
        """The existing 1-D dataset ``ds`` of this group as the coordinate variable of its own name."""
        name = ds.name.rsplit("/", 1)[-1]
        ds.make_scale(name)
        ds.attrs["units"] = units
        self.scales[name] = ds
        return ds


def attach(ds: h5py.Dataset, scales: Sequence[h5py.Dataset], units: str | None = None) -> None:
    """Name each axis of ``ds`` by its scale (one per axis, in order) and set its ``units``."""
    if len(scales) != ds.ndim:
        raise ValueError(f"{ds.name}: {len(scales)} dimension scales for {ds.ndim} axes")
    for axis, scale in enumerate(scales):
        if scale.shape != (ds.shape[axis],):
            raise ValueError(f"{ds.name}: axis {axis} has length {ds.shape[axis]}, its scale {scale.name} "
                             f"{scale.shape[0]}")
        ds.dims[axis].attach_scale(scale)
    if units is not None:
        ds.attrs["units"] = units


__all__ = ["NOT_A_VARIABLE", "Dimensions", "attach"]

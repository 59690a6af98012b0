"""The baseline (typed by part: :class:`Provenance`, :class:`NoiseFit`, :class:`ModelBound`, :class:`HealthyData`,
:class:`DriftModel`) and its file ``baseline.h5``: this module alone reads and writes it.

Root attributes: ``schema = "rotorcheck.baseline"``, ``schema_version = 1``, ``stage`` (``"noise"``
after fit-noise, ``"validated"`` after validate), ``rig_id``, ``rig_sha256``, ``sweep_sha256``
(comma-separated when several healthy sweeps), ``run_id``, ``speed_rpm``, ``noise_bound_m``,
``noise_method``, ``noise_confidence``, ``uncertainty``, ``parameter``, ``enclose``, ``created_utc``.
Datasets (validated stage): ``frequency_hz`` (f), ``gamma`` (f), ``gamma_lower`` (f),
``gamma_status`` (f, text), ``model_frf`` (f, 1, 1) complex (the nominal Me22),
``input_phasor`` (f, n_in) and ``output_phasor`` (f, n_out) copied from the (first) healthy sweep
(after removing shaft-speed harmonics where the sweep stored per-period phasors: root attribute
``shaft_orders_removed``); for measured detection ``healthy_frf`` (f, n_out) complex m/N (mean over
the healthy sweeps), ``healthy_frf_var`` (f, n_out) m^2/N^2 (variance of that mean) and
``healthy_frf_dof`` (f, n_out) (its real degrees of freedom; inf = known); with the 'per-point' noise
method ``noise_bound_per_point_m`` (f) m (``noise_bound_m`` is then its maximum). For the joint
test (several healthy sweeps): ``benign_directions`` (q, f) complex m/N (benign directions learned
from the healthy sweeps' spread), ``benign_direction_bound`` (q,) (bound on each coefficient's real
and imaginary part) and the root attributes ``benign_kappa`` (relative error of the model's benign
prediction carried in H0; absent: the default) and ``n_healthy`` (healthy sweeps); ``healthy_sideband_p_value``
(the healthy sweeps' sideband scan, where they held sidebands);
``benign_correction`` (p, f) complex m/N per unit parameter (the healthy sweeps' correction of the
model's benign change, one row per benign parameter in the order of the rig's variability section at
the baseline's speed).

A file of several runs (speeds) holds the first run's set at the root and each further run's in
``/runs/<run_id>`` (same names). netCDF-4 view (:func:`_label_for_netcdf`, added beside these datasets,
ignored by the reader, absent from files written before it): every group opens in xarray,
``xarray.open_dataset(path, engine="h5netcdf")`` for the first run, ``group="runs/<run_id>"`` for the others,
with the coordinates ``frequency_hz`` (Hz), ``channel`` (the channel pairs as ``output<-input`` port labels),
``output`` and ``input`` (the first pair's ports) and ``units`` on every numeric dataset.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rotorcheck.errors import InputError
from rotorcheck.fileio import atomic_path, check_hdf5_global_heaps, hdf5_attr_problem
from rotorcheck.netcdf_view import Dimensions, attach

SCHEMA = "rotorcheck.baseline"
SCHEMA_VERSION = 1


@dataclass
class Provenance:
    """Where a baseline came from: the rig (id, sha256 of its description, the file it was loaded from), the
    healthy sweeps (sha256 each), the run and its speed (rpm), when (UTC), and the sweep a reused noise bound
    was fitted on (None: fitted on these sweeps)."""

    rig_id: str
    rig_sha256: str
    sweep_sha256: list[str]
    run_id: str
    speed_rpm: float
    created_utc: str = ""
    rig_path: str | None = None
    noise_fitted_on_sweep: str | None = None


@dataclass
class NoiseFit:
    """Step 2: the noise bound V (m), uniform or per point (``per_point_m``, f), at family-wise ``confidence``
    over the points (complex circular Gaussian noise assumed), and the method that fitted it. ``uncertainty``
    and ``parameter``: the rig's uncertainty structure the noise was fitted for."""

    bound_m: float
    method: str
    confidence: float
    per_point_m: np.ndarray | None = None
    uncertainty: str = ""
    parameter: str = ""


@dataclass
class ModelBound:
    """Step 3: the nominal model's error bound gamma_h per frequency (Hz) enclosing the healthy data (``gamma``
    upper, ``gamma_lower`` lower, ``gamma_status`` per point), the uncertainty structure it is measured in
    (``additive`` m/N, ``multiplicative`` relative, ``parametric`` the parameter's unit), the detection mode
    ``enclose`` and the nominal receptance ``model_frf`` (f, 1, 1) m/N."""

    enclose: str
    uncertainty: str
    parameter: str
    frequency_hz: np.ndarray
    gamma: np.ndarray
    model_frf: np.ndarray
    gamma_lower: np.ndarray | None = None
    gamma_status: np.ndarray | None = None


@dataclass
class HealthyData:
    """The measured healthy FRF (f, P) m/N: mean over ``n_healthy`` sweeps, the variance of that mean (m^2/N^2)
    and its real degrees of freedom (inf: stated); the first sweep's phasors (N, m); the shaft orders removed;
    the channel pairs as ``[output, input]`` labels (None: made before pairs were stored); ``sideband_p_value``:
    the sideband scan's p-value of the healthy sweeps (their smallest; None: no healthy sweep held sidebands), the
    check that the healthy rotor is time-invariant (:mod:`rotorcheck.signal.sidebands`)."""

    frf: np.ndarray | None = None
    var: np.ndarray | None = None
    dof: np.ndarray | None = None
    input_phasor: np.ndarray | None = None
    output_phasor: np.ndarray | None = None
    shaft_orders_removed: int = 0
    n_healthy: int = 1
    channel_pairs: list[list[str]] | None = None
    sideband_p_value: float | None = None


@dataclass
class DriftModel:
    """What the joint test allows as benign change: the model-error factor ``kappa`` (None: the default),
    benign directions learned from several healthy sweeps (q, f) m/N with the bound on each coefficient, the
    data's correction of the model's benign change (p, f) m/N per unit parameter, the parameter values
    ``validate --update`` fitted, how much of each benign direction the model predicts, and the ranges' shift
    and widening each side per benign parameter that ``validate --learn-drift`` learned on the modal anchor
    (:mod:`rotorcheck.workflow.drift`; relative changes)."""

    kappa: float | None = None
    directions: np.ndarray | None = None
    direction_bound: np.ndarray | None = None
    correction: np.ndarray | None = None
    updated_parameters: dict[str, float] | None = None
    model_share: dict[str, list[float]] | None = None
    range_shift: dict[str, float] | None = None
    range_widen: dict[str, float] | None = None

    @property
    def on_anchor(self) -> bool:
        """The joint test predicts benign change on the healthy sweep's modal anchor (the default, and drift learned
        by the ranges); False for a baseline whose drift was learned on the model re-solved (kappa, directions or a
        correction without learned ranges: files of earlier versions)."""
        if self.range_shift is not None:
            return True
        return self.kappa is None and self.directions is None and self.correction is None


def _field(part: str, name: str, doc: str) -> property:
    """A read-only view of ``baseline.<part>.<name>`` under the file's name (None where the part is absent)."""
    return property(lambda self: None if getattr(self, part) is None else getattr(getattr(self, part), name),
                    doc=doc)


@dataclass
class Baseline:
    """A baseline typed by part: :class:`Provenance`, :class:`NoiseFit` (step 2), :class:`ModelBound` (step 3;
    None after fit-noise alone), :class:`HealthyData` and :class:`DriftModel`. The flat read-only names
    (``noise_bound_m``, ``gamma``, ``healthy_frf``, ...) are the file's attribute and dataset names."""

    provenance: Provenance
    noise: NoiseFit
    bound: ModelBound | None = None
    healthy: HealthyData = field(default_factory=HealthyData)
    drift: DriftModel = field(default_factory=DriftModel)

    @property
    def validated(self) -> bool:
        """Step 3 done: the baseline holds gamma_h."""
        return self.bound is not None

    @property
    def stage(self) -> str:
        """``noise`` after fit-noise, ``validated`` after validate."""
        return "validated" if self.validated else "noise"

    @property
    def uncertainty(self) -> str:
        """The uncertainty structure (``additive`` | ``multiplicative`` | ``parametric``)."""
        return self.bound.uncertainty if self.bound is not None else self.noise.uncertainty

    @property
    def parameter(self) -> str:
        """The parametric structure's parameter ('' otherwise)."""
        return self.bound.parameter if self.bound is not None else self.noise.parameter

    @property
    def enclose(self) -> str:
        """The detection mode the baseline was validated for ('' before validation)."""
        return self.bound.enclose if self.bound is not None else ""

    rig_id = _field("provenance", "rig_id", "rig id")
    rig_sha256 = _field("provenance", "rig_sha256", "sha256 of the rig description")
    sweep_sha256 = _field("provenance", "sweep_sha256", "sha256 of each healthy sweep")
    run_id = _field("provenance", "run_id", "the healthy run")
    speed_rpm = _field("provenance", "speed_rpm", "speed, rpm")
    created_utc = _field("provenance", "created_utc", "written at (UTC)")
    noise_bound_m = _field("noise", "bound_m", "noise bound V, m")
    noise_method = _field("noise", "method", "how V was fitted")
    noise_confidence = _field("noise", "confidence", "V's family-wise confidence")
    noise_bound_per_point_m = _field("noise", "per_point_m", "V per point, m")
    frequency_hz = _field("bound", "frequency_hz", "grid, Hz")
    gamma = _field("bound", "gamma", "gamma_h upper")
    gamma_lower = _field("bound", "gamma_lower", "gamma_h lower")
    gamma_status = _field("bound", "gamma_status", "gamma_h status per point")
    model_frf = _field("bound", "model_frf", "nominal receptance (f, 1, 1), m/N")
    input_phasor = _field("healthy", "input_phasor", "first healthy sweep's input phasors, N")
    output_phasor = _field("healthy", "output_phasor", "first healthy sweep's output phasors, m")
    healthy_frf = _field("healthy", "frf", "healthy FRF (f, P), m/N")
    healthy_frf_var = _field("healthy", "var", "its variance, m^2/N^2")
    healthy_frf_dof = _field("healthy", "dof", "its real dof")
    shaft_orders_removed = _field("healthy", "shaft_orders_removed", "shaft orders removed")
    n_healthy = _field("healthy", "n_healthy", "healthy sweeps averaged")
    benign_kappa = _field("drift", "kappa", "model-error factor of the benign prediction")
    benign_directions = _field("drift", "directions", "learned benign directions (q, f), m/N")
    benign_direction_bound = _field("drift", "direction_bound", "bound per learned coefficient")
    benign_correction = _field("drift", "correction", "the data's correction of the benign change (p, f)")


#: the file's datasets: (name in the file, part, field)
_DATASETS = (("frequency_hz", "bound", "frequency_hz"), ("gamma", "bound", "gamma"),
             ("gamma_lower", "bound", "gamma_lower"), ("model_frf", "bound", "model_frf"),
             ("input_phasor", "healthy", "input_phasor"), ("output_phasor", "healthy", "output_phasor"),
             ("healthy_frf", "healthy", "frf"), ("healthy_frf_var", "healthy", "var"),
             ("healthy_frf_dof", "healthy", "dof"), ("noise_bound_per_point_m", "noise", "per_point_m"),
             ("benign_directions", "drift", "directions"), ("benign_direction_bound", "drift", "direction_bound"),
             ("benign_correction", "drift", "correction"))
#: typed fields kept as JSON text in ``x_<name>`` attributes (the layout of schema_version 1)
_JSON_ATTRS = (("channel_pairs", "healthy", "channel_pairs"), ("updated_parameters", "drift", "updated_parameters"),
               ("benign_model_share", "drift", "model_share"), ("benign_range_shift", "drift", "range_shift"),
               ("benign_range_widen", "drift", "range_widen"))
#: typed text fields kept in ``x_<name>`` attributes
_TEXT_ATTRS = (("rig_path", "provenance", "rig_path"), ("noise_fitted_on_sweep", "provenance", "noise_fitted_on_sweep"))


def _write_into(h5: h5py.Group, baseline: Baseline) -> None:
    pv, nz = baseline.provenance, baseline.noise
    for name, attr in (("rig_id", pv.rig_id), ("rig_sha256", pv.rig_sha256), ("run_id", pv.run_id),
                        ("speed_rpm", pv.speed_rpm), ("noise_bound_m", nz.bound_m), ("noise_method", nz.method),
                        ("noise_confidence", nz.confidence), ("uncertainty", baseline.uncertainty),
                        ("parameter", baseline.parameter), ("enclose", baseline.enclose), ("stage", baseline.stage),
                        ("created_utc", pv.created_utc)):
        h5.attrs[name] = attr
    h5.attrs["sweep_sha256"] = ",".join(pv.sweep_sha256)
    h5.attrs["shaft_orders_removed"] = int(baseline.healthy.shaft_orders_removed)
    h5.attrs["n_healthy"] = int(baseline.healthy.n_healthy)
    if baseline.healthy.sideband_p_value is not None:
        h5.attrs["healthy_sideband_p_value"] = float(baseline.healthy.sideband_p_value)
    if baseline.drift.kappa is not None:
        h5.attrs["benign_kappa"] = float(baseline.drift.kappa)
    for name, part, key in _TEXT_ATTRS:
        value = getattr(getattr(baseline, part), key)
        if value is not None:
            h5.attrs[f"x_{name}"] = str(value)
    for name, part, key in _JSON_ATTRS:
        value = getattr(getattr(baseline, part), key)
        if value is not None:
            h5.attrs[f"x_{name}"] = json.dumps(value, sort_keys=True)
    for name, part, key in _DATASETS:
        obj = getattr(baseline, part)
        value = None if obj is None else getattr(obj, key)
        if value is not None:
            h5.create_dataset(name, data=value)
    if baseline.gamma_status is not None:
        h5.create_dataset("gamma_status", data=np.asarray(baseline.gamma_status, dtype="S"))
    _label_for_netcdf(h5, baseline)


#: the netCDF view (:mod:`rotorcheck.netcdf_view`): each dataset's axes and ``units`` (gamma's: :func:`gamma_units`)
_VIEW: dict[str, tuple[tuple[str, ...], str | None]] = {
    "gamma": (("frequency_hz",), None), "gamma_lower": (("frequency_hz",), None),
    "gamma_status": (("frequency_hz",), None), "noise_bound_per_point_m": (("frequency_hz",), "m"),
    "model_frf": (("frequency_hz", "output", "input"), "m/N"),
    "input_phasor": (("frequency_hz", "input"), "N"), "output_phasor": (("frequency_hz", "output"), "m"),
    "healthy_frf": (("frequency_hz", "channel"), "m/N"), "healthy_frf_var": (("frequency_hz", "channel"), "m^2/N^2"),
    "healthy_frf_dof": (("frequency_hz", "channel"), "1"),
    "benign_directions": (("direction", "point"), "m/N"), "benign_direction_bound": (("direction",), "1"),
    "benign_correction": (("parameter", "point"), "m/N per unit of the parameter"),
}
#: ``long_name`` of the labels and of the stacked arrays
_LONG_NAMES = {
    "channel": "channel pair, output<-input (model ports)", "output": "output port (the first channel pair's)",
    "input": "input port (the first channel pair's)",
    "benign_directions": "learned benign directions, each over the points channel pair after channel pair",
    "benign_correction": "the data's correction of the benign change per benign parameter (the rig's variability "
                         "order), over the points channel pair after channel pair",
}


def gamma_units(uncertainty: str, parameter: str) -> str:
    """The unit of gamma_h: m/N (additive), 1 (multiplicative), the parameter's (parametric: kg for a mass,
    N/m for a stiffness), '' when unknown."""
    if uncertainty == "additive":
        return "m/N"
    if uncertainty == "multiplicative":
        return "1"
    if uncertainty == "parametric":
        return "kg" if parameter.endswith(".mass") else "N/m"
    return ""


def _label_for_netcdf(h5: h5py.Group, baseline: Baseline) -> None:
    """Dimension scales, channel-pair coordinates and ``units`` on the datasets of one group, so that xarray
    (``engine="h5netcdf"``) opens it: ``frequency_hz`` the coordinate (Hz), ``channel`` the pairs'
    ``output<-input`` labels, ``output``/``input`` the first pair's ports, ``direction``, ``parameter`` and
    ``point`` (the stacked axis of the benign arrays) dimensions without labels."""
    dims = Dimensions(h5)
    freq = dims.coordinate(h5["frequency_hz"], "Hz") if "frequency_hz" in h5 else None
    pairs = baseline.healthy.channel_pairs or []
    labels = {"channel": [f"{o}<-{i}" for o, i in pairs], "output": [o for o, _ in pairs[:1]],
              "input": [i for _, i in pairs[:1]]}
    gamma = gamma_units(baseline.uncertainty, baseline.parameter)
    for name, (axes, units) in _VIEW.items():
        if name not in h5:
            continue
        ds = h5[name]
        if ds.ndim != len(axes):  # not the layout this view knows: numbered axes
            axes = tuple(f"{name}_axis{k}" for k in range(ds.ndim))
        scales = []
        for axis, dname in enumerate(axes):
            size = int(ds.shape[axis])
            if dname == "frequency_hz" and freq is not None and freq.shape == (size,):
                scales.append(freq)
            elif len(labels.get(dname, ())) == size:
                scales.append(dims.labels(dname, labels[dname], {"long_name": _LONG_NAMES[dname]}))
            else:
                scales.append(dims.plain("frequency" if dname == "frequency_hz" else dname, size))
        attach(ds, scales, gamma if name in ("gamma", "gamma_lower") else units)
        if name in _LONG_NAMES:
            ds.attrs["long_name"] = _LONG_NAMES[name]
        if ds.dtype.kind == "S":  # fixed-length bytes: xarray decodes them as text
            ds.attrs["_Encoding"] = "utf-8"


#: attribute holding each item's digest (JSON ``{name: sha256}``) over everything detection reads
DIGEST_ATTR = "content_digests"


def _item_bytes(value: object) -> bytes:
    """Canonical bytes of an attribute or dataset value (type, shape and content)."""
    a = np.asarray(value)
    if a.dtype.kind in "OUS":
        text = repr(a.tolist() if a.ndim else (value.decode() if isinstance(value, bytes) else str(value)))
        return b"str:" + text.encode()
    a = np.ascontiguousarray(a)
    return f"{a.dtype.str}:{a.shape}:".encode() + a.tobytes()


def _digests(h5: h5py.Group) -> dict[str, str]:
    """sha256 of each attribute (``@name``) and dataset of one group (not its subgroups, not the digest)."""
    out = {f"@{k}": hashlib.sha256(_item_bytes(v)).hexdigest() for k, v in h5.attrs.items() if k != DIGEST_ATTR}
    for k, v in h5.items():
        if isinstance(v, h5py.Dataset):
            out[k] = hashlib.sha256(_item_bytes(v[()])).hexdigest()
    return dict(sorted(out.items()))


def _seal(h5: h5py.Group) -> None:
    h5.attrs[DIGEST_ATTR] = json.dumps(_digests(h5))


def _verify(h5: h5py.Group, p: Path, where: str) -> None:
    """Every item detection reads is as rotorcheck wrote it: exit 2 naming what does not match."""
    raw = h5.attrs.get(DIGEST_ATTR)
    if raw is None:
        raise InputError(p, f"{where}/@{DIGEST_ATTR}", "no content digest: written by an older rotorcheck or "
                         "stripped; recreate the baseline (rotorcheck fit-noise and validate)")
    try:
        stored = json.loads(raw.decode() if isinstance(raw, bytes) else str(raw))
        if not isinstance(stored, dict):
            raise ValueError
    except ValueError:
        raise InputError(p, f"{where}/@{DIGEST_ATTR}", "unreadable content digest") from None
    now = _digests(h5)
    changed = sorted(k for k in set(stored) | set(now) if stored.get(k) != now.get(k))
    if changed:
        raise InputError(p, f"{where}/{changed[0]}", "changed since rotorcheck wrote the baseline (content digest "
                         f"mismatch: {', '.join(changed)}); an edited or corrupt baseline is not used: recreate it")


def write_baseline(baseline: Baseline, path: str | Path, others: list[Baseline] | None = None) -> None:
    """Write atomically (temp file in the same folder, then rename). Overwrite policy is the caller's.
    ``others``: the validated sets of a file's further runs (speeds), each in ``/runs/<run_id>``."""
    if not baseline.provenance.created_utc:
        baseline.provenance.created_utc = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h5:
        h5.attrs["schema"] = SCHEMA
        h5.attrs["schema_version"] = SCHEMA_VERSION
        _write_into(h5, baseline)
        for b in others or []:
            b.provenance.created_utc = b.provenance.created_utc or baseline.provenance.created_utc
            g = h5.require_group("runs").create_group(b.run_id)
            _write_into(g, b)
            _seal(g)
        _seal(h5)  # the root's own items (each run group carries its own digest)


def stored_rig(path: str | Path) -> tuple[str | None, str | None]:
    """``(rig_id, rig file)`` a baseline file at ``path`` was made with, without checking the rest of it;
    ``(None, None)`` when there is no such file, it is no HDF5 or those attributes are not safe text (its
    reader then says what is wrong). Read with the reader's own safeguards (heaps walked first, each
    attribute's datatype checked before it is read)."""
    p = Path(path)
    if not p.exists():
        return None, None
    check_hdf5_global_heaps(p)  # before the HDF5 library can loop on a corrupt heap
    try:
        with h5py.File(p, "r") as h5:
            return tuple(  # type: ignore[return-value]
                _attr_text(h5, p, f"/@{name}", name) if name in h5.attrs else None for name in ("rig_id", "x_rig_path"))
    except (OSError, InputError):
        return None, None


def read_baseline(path: str | Path) -> Baseline:
    """Read and check a baseline (its first run); raises InputError naming the file and the field."""
    return read_baselines(path)[0]


def read_baselines(path: str | Path) -> list[Baseline]:
    """Every validated set of a baseline file, the first run first (a file of several speeds holds one
    set per run)."""
    p = Path(path)
    if not p.exists():
        raise InputError(p, "", "baseline not found (run 'rotorcheck validate' first, or pass --baseline)")
    check_hdf5_global_heaps(p)  # before the HDF5 library can loop on a corrupt heap
    try:
        h5 = h5py.File(p, "r")
    except OSError as exc:
        raise InputError(p, "", f"not a readable HDF5 baseline ({exc})") from None
    with h5:
        try:
            return _read_groups(h5, p)
        except InputError:
            raise
        except (OSError, KeyError, ValueError, TypeError, RuntimeError, OverflowError, IndexError) as exc:  # h5py
            raise InputError(p, "", f"corrupt HDF5 baseline ({type(exc).__name__}: {exc})") from None


def _read_groups(h5: h5py.File, p: Path) -> list[Baseline]:
    """The root's set and every /runs/<run_id> set (:func:`read_baselines`)."""
    schema = _attr_value(h5, p, "/@schema", "schema") if "schema" in h5.attrs else None
    if not isinstance(schema, (str, bytes)) or (schema.decode("utf-8", "replace") if isinstance(schema, bytes)
                                                else schema) != SCHEMA:
        raise InputError(p, "/@schema", f"not a rotorcheck baseline (schema {_short(schema)})")
    version = _attr_value(h5, p, "/@schema_version", "schema_version") if "schema_version" in h5.attrs else None
    try:
        known = version is not None and int(version) == SCHEMA_VERSION
    except (TypeError, ValueError, OverflowError):
        known = False
    if not known:
        raise InputError(p, "/@schema_version", f"unknown schema_version {version!r}")
    out = [_read_from(h5, p, "")]
    if "runs" in h5:
        runs = h5.get("runs", getlink=False)
        if not isinstance(runs, h5py.Group):
            raise InputError(p, "/runs", f"must be a group, got {type(runs).__name__}")
        for rid in runs:
            group = runs.get(rid, getlink=False)
            if not isinstance(group, h5py.Group):
                raise InputError(p, f"/runs/{rid}", f"must be a group, got {type(group).__name__}")
            out.append(_read_from(group, p, f"/runs/{rid}"))
    return out


_COMPLEX_DATASETS = ("model_frf", "input_phasor", "output_phasor", "healthy_frf", "benign_directions",
                     "benign_correction")
#: the most elements a baseline dataset may have (read only after this is checked)
MAX_DATASET_ELEMENTS = 50_000_000


def _attr_text(h5: h5py.Group, p: Path, field: str, name: str, default: str | None = None) -> str:
    if name not in h5.attrs:
        if default is None:
            raise InputError(p, field, "missing attribute")
        return default
    v = _attr_value(h5, p, field, name)
    if isinstance(v, np.ndarray) and v.shape == () and v.dtype.kind in "SUO":
        v = v.item()
    if isinstance(v, bytes):
        try:
            v = v.decode("utf-8")
        except UnicodeDecodeError:
            raise InputError(p, field, "not UTF-8 text") from None
    if not isinstance(v, str):
        raise InputError(p, field, f"must be text, got {type(v).__name__} {_short(v)}")
    return v


def _attr_value(h5: h5py.Group, p: Path, field: str, name: str) -> Any:
    """The attribute's value once its datatype is one a baseline holds and sane (libhdf5 can crash on others)."""
    problem = hdf5_attr_problem(h5, name)
    if problem:
        raise InputError(p, field, problem)
    return h5.attrs[name]


def _attr_number(h5: h5py.Group, p: Path, field: str, name: str, integer: bool = False) -> float:
    v = _attr_value(h5, p, field, name)
    if isinstance(v, np.ndarray) and v.shape == ():
        v = v[()]
    ok = isinstance(v, (int, np.integer)) if integer else isinstance(v, (int, float, np.integer, np.floating))
    if not ok or isinstance(v, (bool, np.bool_)):
        raise InputError(p, field, f"must be {'an integer' if integer else 'a real number'}, got "
                         f"{type(v).__name__} {_short(v)}")
    return int(v) if integer else float(v)


def _short(v: object) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _read_dataset(h5: h5py.Group, p: Path, where: str, name: str) -> np.ndarray:
    """A dataset's array once its kind, dtype and size are checked (a group, a string or a huge dataset is an
    InputError naming it)."""
    item = h5.get(name, getlink=False)
    field = f"{where}/{name}"
    if not isinstance(item, h5py.Dataset):
        raise InputError(p, field, f"must be a dataset, got {type(item).__name__}")
    kind = item.dtype.kind
    want = "S" if name == "gamma_status" else ("fc" if name in _COMPLEX_DATASETS else "fiu")
    if kind not in want:
        raise InputError(p, field, f"dtype {item.dtype} is not {'text' if want == 'S' else 'numeric'}")
    if item.size > MAX_DATASET_ELEMENTS:
        raise InputError(p, field, f"{item.size} elements: more than a baseline holds ({MAX_DATASET_ELEMENTS})")
    try:
        data = np.asarray(item[()])
    except (OSError, ValueError, TypeError) as exc:  # a corrupt chunk, an unreadable filter
        raise InputError(p, field, f"unreadable ({type(exc).__name__}: {exc})") from None
    if want == "S":
        try:
            return np.char.decode(data, "utf-8")
        except UnicodeDecodeError:
            raise InputError(p, field, "not UTF-8 text") from None
    return data


def _json_attr(h5: h5py.Group, p: Path, where: str, name: str, check: type) -> Any:
    """A typed field kept as JSON text in ``x_<name>`` (None when absent)."""
    if f"x_{name}" not in h5.attrs:
        return None
    try:
        value = json.loads(_attr_text(h5, p, f"{where}/@x_{name}", f"x_{name}"))
    except ValueError:
        raise InputError(p, f"{where}/@x_{name}", "not JSON") from None
    if not isinstance(value, check):
        raise InputError(p, f"{where}/@x_{name}", f"must be a JSON {check.__name__}")
    return value


def _number_dict(h5: h5py.Group, p: Path, where: str, name: str) -> dict[str, float] | None:
    """A ``{name: finite number}`` field kept as JSON text in ``x_<name>`` (None when absent)."""
    value = _json_attr(h5, p, where, name, dict)
    if value is None:
        return None
    bad = [k for k, v in value.items() if isinstance(v, bool) or not isinstance(v, (int, float))
           or not np.isfinite(v)]
    if bad:
        raise InputError(p, f"{where}/@x_{name}", f"{bad[0]!r} must be a finite number")
    return {str(k): float(v) for k, v in value.items()}


def _read_from(h5: h5py.Group, p: Path, where: str) -> Baseline:
    """One validated set from a group of the baseline file (``where``: its path, for messages). Every
    attribute and dataset is type-checked before it is used."""
    for name in h5.attrs:  # every attribute is read by the digest check: each must be safe to read
        problem = hdf5_attr_problem(h5, name)
        if problem:
            raise InputError(p, f"{where}/@{name}", problem)

    def text(name: str, default: str | None = None) -> str:
        return _attr_text(h5, p, f"{where}/@{name}", name, default)

    def number(name: str) -> float:
        if name not in h5.attrs:
            raise InputError(p, f"{where}/@{name}", "missing attribute")
        return _attr_number(h5, p, f"{where}/@{name}", name)

    def count(name: str, low: int) -> int:
        if name not in h5.attrs:
            return low
        n = int(_attr_number(h5, p, f"{where}/@{name}", name, integer=True))
        if n < low:
            raise InputError(p, f"{where}/@{name}", f"must be >= {low}, got {n}")
        return n

    def data(name: str) -> np.ndarray | None:
        return _read_dataset(h5, p, where, name) if name in h5 else None

    stage = text("stage")
    if stage not in ("noise", "validated"):
        raise InputError(p, f"{where}/@stage", f"must be 'noise' or 'validated', got {_short(stage)}")
    speed = number("speed_rpm")
    if not np.isfinite(speed):
        raise InputError(p, f"{where}/@speed_rpm", f"must be finite, got {speed}")
    prov = Provenance(text("rig_id"), text("rig_sha256"), [s for s in text("sweep_sha256", "").split(",") if s],
                      text("run_id"), speed, text("created_utc"),
                      text("x_rig_path") if "x_rig_path" in h5.attrs else None,
                      text("x_noise_fitted_on_sweep") if "x_noise_fitted_on_sweep" in h5.attrs else None)
    noise = NoiseFit(number("noise_bound_m"), text("noise_method"), number("noise_confidence"),
                     data("noise_bound_per_point_m"), text("uncertainty"), text("parameter"))
    pairs = _json_attr(h5, p, where, "channel_pairs", list)
    healthy = HealthyData(data("healthy_frf"), data("healthy_frf_var"), data("healthy_frf_dof"), data("input_phasor"),
                          data("output_phasor"), count("shaft_orders_removed", 0), count("n_healthy", 1),
                          None if pairs is None else [[str(x) for x in pr] for pr in pairs],
                          number("healthy_sideband_p_value") if "healthy_sideband_p_value" in h5.attrs else None)
    drift = DriftModel(number("benign_kappa") if "benign_kappa" in h5.attrs else None,
                       data("benign_directions"), data("benign_direction_bound"), data("benign_correction"),
                       _number_dict(h5, p, where, "updated_parameters"),
                       _json_attr(h5, p, where, "benign_model_share", dict),
                       _number_dict(h5, p, where, "benign_range_shift"),
                       _number_dict(h5, p, where, "benign_range_widen"))
    bound = None
    if stage == "validated":
        for name in ("frequency_hz", "gamma", "model_frf"):
            if name not in h5:
                raise InputError(p, f"{where}/{name}", "missing dataset in a validated baseline")
        freq, gamma, model = (_read_dataset(h5, p, where, n) for n in ("frequency_hz", "gamma", "model_frf"))
        bound = ModelBound(text("enclose"), text("uncertainty"), text("parameter"), freq, gamma, model,
                           data("gamma_lower"), data("gamma_status"))
    b = Baseline(prov, noise, bound, healthy, drift)
    for name in ("frequency_hz", "gamma", "gamma_lower", "noise_bound_per_point_m", "benign_direction_bound"):
        arr = getattr(b, name)
        if arr is not None and arr.ndim != 1:
            raise InputError(p, f"{where}/{name}", f"must be 1-D, got shape {arr.shape}")
    for name in ("healthy_frf", "healthy_frf_var", "healthy_frf_dof", "model_frf", "input_phasor", "output_phasor"):
        arr = getattr(b, name)
        if arr is not None and arr.ndim < 1:
            raise InputError(p, f"{where}/{name}", "must be an array over the frequencies, got a scalar")
    if b.validated:
        for name in ("frequency_hz", "gamma", "model_frf"):
            if getattr(b, name) is None:
                raise InputError(p, f"{where}/{name}", "missing dataset in a validated baseline")
        assert bound is not None
        n = len(bound.frequency_hz)
        if bound.gamma.shape != (n,):
            raise InputError(p, f"{where}/gamma", f"shape {bound.gamma.shape} does not match frequency_hz ({n},)")
        if b.enclose == "measured":
            for name in ("healthy_frf", "healthy_frf_var", "healthy_frf_dof"):
                arr = getattr(b, name)
                if arr is None:
                    raise InputError(p, f"{where}/{name}", "missing dataset in a baseline for measured detection")
                if arr.shape[0] != n:
                    raise InputError(p, f"{where}/{name}", f"shape {arr.shape} does not match frequency_hz ({n},)")
            var = b.healthy_frf_var
            if var is not None and np.any((var < 0) | np.isinf(var)):
                raise InputError(p, f"{where}/healthy_frf_var", "variances must be >= 0 and finite (NaN: no estimate)")
    bd, bb = b.benign_directions, b.benign_direction_bound
    if (bd is None) != (bb is None):
        raise InputError(p, f"{where}/benign_directions", "benign_directions and benign_direction_bound go together")
    if bd is not None and bb is not None and b.frequency_hz is not None and (
            bd.ndim != 2 or bd.shape[1] % max(len(b.frequency_hz), 1) != 0 or bb.shape != (bd.shape[0],)):
        raise InputError(p, f"{where}/benign_directions", f"shape {bd.shape} (bound {bb.shape}) does not match "
                         f"frequency_hz ({len(b.frequency_hz)},)")
    if b.benign_kappa is not None and not (np.isfinite(b.benign_kappa) and b.benign_kappa >= 0):
        raise InputError(p, f"{where}/@benign_kappa", f"must be finite and >= 0, got {b.benign_kappa}")
    per = b.noise_bound_per_point_m
    if per is not None and (per.ndim != 1 or np.any(per < 0) or np.any(np.isinf(per))):
        raise InputError(p, f"{where}/noise_bound_per_point_m", "must be a 1-D array of values >= 0 (NaN: no estimate)")
    if not np.isfinite(b.noise_bound_m) or b.noise_bound_m < 0:
        raise InputError(p, f"{where}/@noise_bound_m", f"must be finite and >= 0, got {b.noise_bound_m}")
    _verify(h5, p, where)
    return b

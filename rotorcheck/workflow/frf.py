"""The measured FRF of one run as a typed object: always (frequency, channel pairs), with the variance of each
mean FRF (m^2/N^2), its real degrees of freedom, the channel labels and the run's metadata.

>>> from rotorcheck import workflow
>>> from rotorcheck.resources import configs_dir, samples_dir
>>> rig = workflow.load_rig(configs_dir() / "crack_rig.yaml")
>>> frf = workflow.load_run(samples_dir() / "crack_rig" / "healthy_1000rpm.h5", rig).measured_frf()
>>> frf.frf.shape, frf.channels
((262, 1), ['s6.x<-s8.x'])
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # optional: matplotlib for .plot(), pandas and xarray for the exports
    import pandas as pd
    import xarray as xr
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class MeasuredFRF:
    """Receptance FRFs of one run, (f, P): ``frf`` complex m/N, ``var`` the variance of each mean FRF
    (m^2/N^2), ``dof`` its real degrees of freedom (inf: stated, not estimated), ``channels`` one label
    ``"<output><-<input>"`` per pair (the rig's actuator -> sensor first); metadata: the sweep file, its
    sha256, rig, run, speed (rpm), the analysis band (Hz), the shaft orders removed and where an FRF-only
    run's noise came from."""

    frequency_hz: np.ndarray
    frf: np.ndarray
    var: np.ndarray
    dof: np.ndarray
    channels: list[str]
    sweep: Path
    sweep_sha256: str
    rig_id: str
    run_id: str
    speed_rpm: float
    band_hz: tuple[float, float]
    harmonics_removed: int = 0
    noise_source: str = ""

    @property
    def std(self) -> np.ndarray:
        """Standard deviation of each mean FRF (f, P), m/N."""
        return np.sqrt(self.var)

    def to_pandas(self) -> pd.DataFrame:
        """A tidy table: one row per frequency and channel pair (frequency_hz, channel, re, im, magnitude,
        phase_deg, var, dof), receptances in m/N."""
        import pandas as pd  # lazy: pandas is an optional dependency (with xarray: the 'dev' extra)

        nf, npair = self.frf.shape
        return pd.DataFrame({
            "frequency_hz": np.repeat(self.frequency_hz, npair),
            "channel": np.tile(np.asarray(self.channels, dtype=object), nf),
            "re": self.frf.real.ravel(), "im": self.frf.imag.ravel(), "magnitude": np.abs(self.frf).ravel(),
            "phase_deg": np.degrees(np.angle(self.frf)).ravel(), "var": self.var.ravel(), "dof": self.dof.ravel()})

    def to_xarray(self) -> xr.Dataset:
        """A Dataset with coordinates ``frequency`` (Hz) and ``channel`` (the pair labels) and the variables
        ``frf`` (m/N), ``frf_var`` (m^2/N^2), ``frf_dof``, units in each variable's attributes."""
        import xarray as xr  # lazy: xarray is an optional dependency (the 'dev' extra)

        coords = {"frequency": ("frequency", self.frequency_hz, {"units": "Hz"}), "channel": self.channels}
        dims = ("frequency", "channel")
        attrs: dict[str, Any] = {"sweep": str(self.sweep), "sweep_sha256": self.sweep_sha256, "rig_id": self.rig_id,
                                 "run_id": self.run_id, "speed_rpm": self.speed_rpm, "band_hz": list(self.band_hz),
                                 "harmonics_removed": self.harmonics_removed, "noise_source": self.noise_source,
                                 "phasor_convention": "x(t) = Re{X exp(j 2 pi f t)}, peak"}
        return xr.Dataset({"frf": (dims, self.frf, {"units": "m/N"}),
                           "frf_var": (dims, self.var, {"units": "m^2/N^2"}),
                           "frf_dof": (dims, self.dof, {"units": "1"})}, coords=coords, attrs=attrs)

    def plot(self) -> Figure:
        """Bode magnitude and phase of every channel pair with a +-2 standard-deviation band on the magnitude."""
        import matplotlib.pyplot as plt  # lazy: matplotlib only when plotting

        fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
        for k, name in enumerate(self.channels):
            mag, sd = np.abs(self.frf[:, k]), self.std[:, k]
            (line,) = ax_m.semilogy(self.frequency_hz, mag, label=name)
            ax_m.fill_between(self.frequency_hz, np.maximum(mag - 2 * sd, mag * 1e-3), mag + 2 * sd,
                              color=line.get_color(), alpha=0.25, linewidth=0)
            ax_p.plot(self.frequency_hz, np.degrees(np.unwrap(np.angle(self.frf[:, k]))), color=line.get_color())
        ax_m.set_ylabel("|receptance| (m/N), band +-2 sd")
        ax_p.set_ylabel("phase (deg, unwrapped; response lags negative)")
        ax_p.set_xlabel("frequency (Hz)")
        ax_m.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
        fig.suptitle(f"{self.rig_id}, run {self.run_id}, {self.speed_rpm:g} rpm: {self.sweep.name}")
        fig.tight_layout()
        return fig

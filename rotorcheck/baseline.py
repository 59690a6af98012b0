"""The baseline file (``baseline.h5``): noise bound (step 2) and healthy uncertainty bound (step 3).

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
prediction carried in H0; absent: the default) and ``n_healthy`` (healthy sweeps);
``benign_correction`` (p, f) complex m/N per unit parameter (the healthy sweeps' correction of the
model's benign change, one row per benign parameter in the order of the rig's variability section at
the baseline's speed).
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from rotorcheck.errors import InputError
from rotorcheck.fileio import atomic_path

SCHEMA = "rotorcheck.baseline"
SCHEMA_VERSION = 1


@dataclass
class Baseline:
    """Noise bound and, once validated, the per-frequency uncertainty bound gamma."""

    rig_id: str
    rig_sha256: str
    sweep_sha256: list[str]
    run_id: str
    speed_rpm: float
    noise_bound_m: float
    noise_method: str
    noise_confidence: float
    uncertainty: str
    parameter: str = ""
    enclose: str = ""
    stage: str = "noise"
    created_utc: str = ""
    frequency_hz: np.ndarray | None = None
    gamma: np.ndarray | None = None
    gamma_lower: np.ndarray | None = None
    gamma_status: np.ndarray | None = None
    model_frf: np.ndarray | None = None
    input_phasor: np.ndarray | None = None
    output_phasor: np.ndarray | None = None
    healthy_frf: np.ndarray | None = None
    healthy_frf_var: np.ndarray | None = None
    healthy_frf_dof: np.ndarray | None = None
    shaft_orders_removed: int = 0
    noise_bound_per_point_m: np.ndarray | None = None
    benign_directions: np.ndarray | None = None
    benign_direction_bound: np.ndarray | None = None
    benign_kappa: float | None = None
    benign_correction: np.ndarray | None = None
    n_healthy: int = 1
    extra: dict[str, str] = field(default_factory=dict)

    @property
    def validated(self) -> bool:
        return self.stage == "validated"


_ATTRS = ("rig_id", "rig_sha256", "run_id", "speed_rpm", "noise_bound_m", "noise_method",
          "noise_confidence", "uncertainty", "parameter", "enclose", "stage", "created_utc")
_DATASETS = ("frequency_hz", "gamma", "gamma_lower", "model_frf", "input_phasor", "output_phasor",
             "healthy_frf", "healthy_frf_var", "healthy_frf_dof", "noise_bound_per_point_m", "benign_directions",
             "benign_direction_bound", "benign_correction")


def _write_into(h5: h5py.Group, baseline: Baseline) -> None:
    for name in _ATTRS:
        h5.attrs[name] = getattr(baseline, name)
    h5.attrs["sweep_sha256"] = ",".join(baseline.sweep_sha256)
    h5.attrs["shaft_orders_removed"] = int(baseline.shaft_orders_removed)
    h5.attrs["n_healthy"] = int(baseline.n_healthy)
    if baseline.benign_kappa is not None:
        h5.attrs["benign_kappa"] = float(baseline.benign_kappa)
    for k, v in baseline.extra.items():
        h5.attrs[f"x_{k}"] = v
    for name in _DATASETS:
        value = getattr(baseline, name)
        if value is not None:
            h5.create_dataset(name, data=value)
    if baseline.gamma_status is not None:
        h5.create_dataset("gamma_status", data=np.asarray(baseline.gamma_status, dtype="S"))


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
    import hashlib

    out = {f"@{k}": hashlib.sha256(_item_bytes(v)).hexdigest() for k, v in h5.attrs.items() if k != DIGEST_ATTR}
    for k, v in h5.items():
        if isinstance(v, h5py.Dataset):
            out[k] = hashlib.sha256(_item_bytes(v[()])).hexdigest()
    return dict(sorted(out.items()))


def _seal(h5: h5py.Group) -> None:
    import json

    h5.attrs[DIGEST_ATTR] = json.dumps(_digests(h5))


def _verify(h5: h5py.Group, p: Path, where: str) -> None:
    """Every item detection reads is as rotorcheck wrote it: exit 2 naming what does not match."""
    import json

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
    if not baseline.created_utc:
        baseline.created_utc = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h5:
        h5.attrs["schema"] = SCHEMA
        h5.attrs["schema_version"] = SCHEMA_VERSION
        _write_into(h5, baseline)
        for b in others or []:
            b.created_utc = b.created_utc or baseline.created_utc
            g = h5.require_group("runs").create_group(b.run_id)
            _write_into(g, b)
            _seal(g)
        _seal(h5)  # the root's own items (each run group carries its own digest)


def read_baseline(path: str | Path) -> Baseline:
    """Read and check a baseline (its first run); raises InputError naming the file and the field."""
    return read_baselines(path)[0]


def read_baselines(path: str | Path) -> list[Baseline]:
    """Every validated set of a baseline file, the first run first (a file of several speeds holds one
    set per run)."""
    p = Path(path)
    if not p.exists():
        raise InputError(p, "", "baseline not found (run 'rotorcheck validate' first, or pass --baseline)")
    try:
        h5 = h5py.File(p, "r")
    except OSError as exc:
        raise InputError(p, "", f"not a readable HDF5 baseline ({exc})") from None
    with h5:
        if h5.attrs.get("schema") != SCHEMA:
            raise InputError(p, "/@schema", f"not a rotorcheck baseline (schema {h5.attrs.get('schema')!r})")
        version = h5.attrs.get("schema_version")
        try:
            known = int(version) == SCHEMA_VERSION
        except (TypeError, ValueError):
            known = False
        if not known:
            raise InputError(p, "/@schema_version", f"unknown schema_version {version!r}")
        out = [_read_from(h5, p, "")]
        if "runs" in h5:
            out += [_read_from(h5["runs"][rid], p, f"/runs/{rid}") for rid in h5["runs"]]
    return out


def _read_from(h5: h5py.Group, p: Path, where: str) -> Baseline:
    """One validated set from a group of the baseline file (``where``: its path, for messages)."""
    values: dict[str, object] = {}
    for name in _ATTRS:
        if name not in h5.attrs:
            raise InputError(p, f"{where}/@{name}", "missing attribute")
        v = h5.attrs[name]
        values[name] = v.decode() if isinstance(v, bytes) else (v.item() if hasattr(v, "item") else v)
    sweeps = str(h5.attrs.get("sweep_sha256", ""))
    b = Baseline(sweep_sha256=[s for s in sweeps.split(",") if s], **values)  # type: ignore[arg-type]
    b.extra = {k[2:]: str(v) for k, v in h5.attrs.items() if k.startswith("x_")}
    b.shaft_orders_removed = int(h5.attrs.get("shaft_orders_removed", 0))
    b.n_healthy = int(h5.attrs.get("n_healthy", 1))
    if "benign_kappa" in h5.attrs:
        b.benign_kappa = float(h5.attrs["benign_kappa"])
    for name in _DATASETS:
        if name in h5:
            setattr(b, name, h5[name][()])
    if "gamma_status" in h5:
        b.gamma_status = np.char.decode(h5["gamma_status"][()], "utf-8")
    if b.validated:
        for name in ("frequency_hz", "gamma", "model_frf"):
            if getattr(b, name) is None:
                raise InputError(p, f"{where}/{name}", "missing dataset in a validated baseline")
        n = len(b.frequency_hz)  # type: ignore[arg-type]
        if b.gamma.shape != (n,):  # type: ignore[union-attr]
            raise InputError(p, f"{where}/gamma",
                             f"shape {b.gamma.shape} does not match frequency_hz ({n},)")  # type: ignore[union-attr]
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

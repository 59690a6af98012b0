"""Simulated stepped-sine time recordings of a (truth) rig and their channel map, for ``rotorcheck ingest``.

    python -m tools.time_records OUT_DIR [--format csv] [--speed 1000] [--fault breathing_crack]
                                 [--points 8] [--seed 0] [--fs 25600] [--no-steps] [--shaft-angle DEG]
                                 [--sidebands -2,-1,1,2]

writes ``OUT_DIR/record.<ext>`` and ``OUT_DIR/channels.yaml`` (the map, with the exact step table unless
``--no-steps``; with ``--sidebands`` the map asks for those sideband orders); then
``rotorcheck ingest OUT_DIR/record.<ext> sweep.h5 --map OUT_DIR/channels.yaml``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import yaml

from rotorcheck.config import load_config
from rotorcheck.resources import configs_dir
from rotorcheck.sim.time_records import (
    RECORD_FORMATS,
    RecordSpec,
    channel_map_dict,
    record_suffix,
    simulate_rig_record,
    write_record,
)


def make(out_dir: str | Path, fmt: str = "hdf5", speed: float = 0.0, fault: str | None = None, points: int = 8,
         seed: int = 0, fs_hz: float = 25600.0, steps: bool = True, rig: str | Path | None = None,
         f_min: float = 30.0, f_max: float = 600.0, shaft_angle_rad: float = 0.0,
         sideband_orders: Sequence[int] = ()) -> tuple[Path, Path]:
    """Write one simulated record and its channel map (``sideband_orders``: the map's
    ``analysis.sideband_orders``); returns their paths."""
    cfg = load_config(rig if rig is not None else configs_dir() / "crack_rig_truth.yaml")
    grid = np.linspace(f_min, f_max, points)
    sen = cfg.io_ports("a simulated time record").sensor
    spec = RecordSpec(fs_hz=fs_hz, probe_names=(f"disp_s{sen.station}_{sen.direction}",))
    sim = simulate_rig_record(cfg, grid, speed, fault, seed, spec, shaft_angle_rad=shaft_angle_rad)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rec = write_record(sim, out / f"record{record_suffix(fmt)}", fmt)
    cmap = out / "channels.yaml"
    extra = {"sideband_orders": [int(k) for k in sideband_orders]} if sideband_orders else {}
    doc = channel_map_dict(sim, cfg.rig_id.replace("_truth", ""), fmt, with_steps=steps, **extra)
    cmap.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return Path(rec), cmap


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out_dir")
    ap.add_argument("--format", default="hdf5", choices=RECORD_FORMATS)
    ap.add_argument("--speed", type=float, default=0.0)
    ap.add_argument("--fault", default=None)
    ap.add_argument("--points", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--fs", type=float, default=25600.0)
    ap.add_argument("--no-steps", action="store_true", help="leave the step table out (steps found in the force)")
    ap.add_argument("--shaft-angle", type=float, default=0.0, help="shaft angle at the start, deg")
    ap.add_argument("--sidebands", default="", help="sideband orders for the map, e.g. -2,-1,1,2")
    a = ap.parse_args(argv)
    orders = [int(k) for k in a.sidebands.split(",") if k.strip()]
    rec, cmap = make(a.out_dir, a.format, a.speed, a.fault, a.points, a.seed, a.fs, not a.no_steps,
                     shaft_angle_rad=float(np.radians(a.shaft_angle)), sideband_orders=orders)
    print(f"wrote {rec} and {cmap}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())

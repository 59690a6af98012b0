"""Reference numbers from ROSS (ross-rotordynamics) for tests/fe/test_ross_suite.py.

Not part of rotorcheck and not run by the tests: it needs ROSS (``pip install ross-rotordynamics``,
in its own environment) and writes ``tests/data/ross/ross_reference.json``. The tests check
rotorcheck against the numbers ROSS's own test suite asserts (copied there with their source) and,
where ROSS's suite asserts none (the 64-element cone, the compressor, the pedestal rotor, bearing
mass), against this file, produced by ROSS 2.3.0. Each mode is classified lateral / axial-torsional
from its shape (share of the eigenvector in z and the torsion angle) so that the lateral model can be
compared with the lateral modes only.

Run: ``/path/to/ross-venv/bin/python tools/ross_reference.py``
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import ross as rs
from ross.materials import Material

OUT = Path(__file__).resolve().parents[1] / "tests" / "data" / "ross" / "ross_reference.json"
steel = Material("steel", rho=7810, E=211e9, G_s=81.2e9)
RPM = 2 * np.pi / 60


def lateral(rotor: rs.Rotor, speed: float, n: int = 12) -> dict[str, list[float]]:
    """Damped (wd) and undamped (wn) frequencies, rad/s, of the lateral modes only."""
    modal = rotor.run_modal(speed, num_modes=2 * n + 12)
    lat = np.isin(np.arange(rotor.ndof) % 6, [0, 1, 3, 4])
    share = []
    for sh in modal.shapes:
        v = np.asarray(sh.vector)[: rotor.ndof]
        share.append(np.sum(np.abs(v[lat]) ** 2) / np.sum(np.abs(v) ** 2))
    keep = np.asarray(share) > 0.5
    return {
        "wd": [float(x) for x in modal.wd[: keep.size][keep][:n]],
        "wn": [float(x) for x in modal.wn[: keep.size][keep][:n]],
        "log_dec": [float(x) for x in modal.log_dec[: keep.size][keep][:n]],
        "axial_torsional_wd": [float(x) for x in modal.wd[: keep.size][~keep][:4]],
        "whirl": [str(x).lower() for x in np.asarray(modal.whirl_direction())[: keep.size][keep][:n]],
    }


def rotor_example(**shaft_kw: object) -> rs.Rotor:
    shaft = [rs.ShaftElement(0.25, 0, 0.05, material=steel, **shaft_kw) for _ in range(6)]
    disks = [rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28),
             rs.DiskElement.from_geometry(n=4, material=steel, width=0.07, i_d=0.05, o_d=0.28)]
    bearings = [rs.BearingElement(0, kxx=1e6, kyy=0.8e6, cxx=0), rs.BearingElement(6, kxx=1e6, kyy=0.8e6, cxx=0)]
    return rs.Rotor(shaft, disks, bearings)


def loaded(kind: str) -> rs.Rotor:
    """The rotors of ROSS's test_axial_force / test_torque."""
    kw = {"axial_force": 100e3} if kind == "axial_force" else {"torque": 100e3}
    shaft = [rs.ShaftElement(L=0.25, idl=0, odl=0.05, material=steel, **kw) for _ in range(6)]
    disks = [rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28),
             rs.DiskElement.from_geometry(n=4, material=steel, width=0.07, i_d=0.05, o_d=0.35)]
    bearings = [rs.BearingElement(n=0, kxx=1e6, cxx=0), rs.BearingElement(n=6, kxx=1e6, cxx=0)]
    return rs.Rotor(shaft_elements=shaft, disk_elements=disks, bearing_elements=bearings)


def conical(n: int) -> rs.Rotor:
    d = (0.1 - 0.01) / n
    shaft = [rs.ShaftElement(n=i, idl=0.0, odl=0.1 - i * d, idr=0.0, odr=0.1 - (i + 1) * d, material=steel,
                             L=0.5 / n) for i in range(n)]
    bearings = [rs.BearingElement(n=0, kxx=1e20, kyy=1e20, cxx=0), rs.BearingElement(n=n, kxx=1e20, kyy=1e20, cxx=0)]
    return rs.Rotor(shaft_elements=shaft, bearing_elements=bearings)


def pedestals() -> rs.Rotor:
    """ROSS's test_global_index rotor: bearings linked to 1 kg pedestals on supports."""
    shaft = [rs.ShaftElement(0.25, 0, 0.05, material=steel) for _ in range(6)]
    disks = [rs.DiskElement.from_geometry(n=2, material=steel, width=0.07, i_d=0.05, o_d=0.28),
             rs.DiskElement.from_geometry(n=4, material=steel, width=0.07, i_d=0.05, o_d=0.28)]
    b = [rs.BearingElement(0, n_link=7, kxx=1e6, kyy=0.8e6, cxx=0),
         rs.BearingElement(6, n_link=8, kxx=1e6, kyy=0.8e6, cxx=0),
         rs.BearingElement(7, kxx=1e6, kyy=0.8e6, cxx=0, tag="Support0"),
         rs.BearingElement(8, kxx=1e6, kyy=0.8e6, cxx=0, tag="Support1")]
    pm = [rs.PointMass(7, m=1.0), rs.PointMass(8, m=1.0)]
    return rs.Rotor(shaft, disks, b, pm)


def bearing_mass() -> rs.Rotor:
    """ROSS's fixture rotor2_bearing_mass: 2 elements, a disc, bearings with 20 g mass."""
    shaft = [rs.ShaftElement(0.25, 0, 0.05, material=steel) for _ in range(2)]
    disk = rs.DiskElement.from_geometry(1, steel, 0.07, 0.05, 0.28)
    b = [rs.BearingElement(0, kxx=1e6, cxx=0, mxx=20e-3), rs.BearingElement(2, kxx=1e6, cxx=0, mxx=20e-3)]
    return rs.Rotor(shaft, [disk], b)


def main() -> int:
    out: dict[str, object] = {"ross_version": rs.__version__, "units": "rad/s"}
    out["rotor_example_0rpm"] = lateral(rotor_example(), 0.0)
    out["rotor_example_4000rpm"] = lateral(rotor_example(), 4000 * RPM)
    out["rotor_example_euler_bernoulli_0rpm"] = lateral(
        rotor_example(shear_effects=False, rotary_inertia=False, gyroscopic=False), 0.0)
    out["axial_force_4000rpm"] = lateral(loaded("axial_force"), 4000 * RPM)
    out["torque_4000rpm"] = lateral(loaded("torque"), 4000 * RPM)
    out["conical_4_0rpm"] = lateral(conical(4), 0.0)
    out["conical_64_0rpm"] = lateral(conical(64), 0.0)
    out["pedestals_0rpm"] = lateral(pedestals(), 0.0)
    out["pedestals_4000rpm"] = lateral(pedestals(), 4000 * RPM)
    out["bearing_mass_0rpm"] = lateral(bearing_mass(), 0.0)
    comp = rs.compressor_example()
    for rpm in (0.0, 6000.0, 9000.0):
        out[f"compressor_{rpm:.0f}rpm"] = lateral(comp, rpm * RPM, 8)
    OUT.write_text(json.dumps(out, indent=1) + "\n")
    # ROSS-saved rotors (Rotor.save) for the import-ross tests
    for name, rotor in (("rotor_example", rotor_example()), ("axial_force", loaded("axial_force")),
                        ("torque", loaded("torque")), ("conical_4", conical(4)), ("pedestals", pedestals()),
                        ("bearing_mass", bearing_mass()), ("compressor", comp)):
        rotor.save(OUT.parent / f"{name}.toml")
    print(f"wrote {OUT}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

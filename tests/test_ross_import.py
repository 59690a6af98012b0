"""Import of rotors saved by ROSS (``Rotor.save``, TOML): rotorcheck.ross_import.

References are independent of the importer: counts, masses and node numbers are computed here from
the TOML, ROSS's bearing interpolant is rebuilt here with scipy as ROSS 2.3.0 builds it
(``UnivariateSpline(frequency, coefficient)``), and the natural frequencies come from ROSS 2.3.0
itself (``tests/data/ross/ross_reference.json``, written by ``tools/ross_reference.py``).
"""

from __future__ import annotations

import json
import math
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.interpolate import UnivariateSpline

from rotorcheck.config import load_config, parse_config
from rotorcheck.errors import InputError
from rotorcheck.ross_import import RossImport, import_ross

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

DATA = Path(__file__).resolve().parent / "data" / "ross"
FILES = sorted(DATA.glob("*.toml"))
COEFFS = ("kxx", "kyy", "kxy", "kyx", "cxx", "cyy", "cxy", "cyx", "mxx", "myy", "mxy", "myx")
RAD_S_TO_RPM = 30.0 / math.pi


def _toml(name: str) -> dict[str, Any]:
    return tomllib.loads((DATA / name).read_text())


def _tables(doc: dict[str, Any], *classes: str) -> dict[str, dict[str, Any]]:
    return {k: v for k, v in doc.items() if isinstance(v, dict) and k.split("_", 1)[0] in classes}


@pytest.fixture(scope="module")
def compressor() -> RossImport:
    return import_ross(DATA / "compressor.toml")


# --------------------------------------------------------------------------------------------
# 1. every sample imports, validates and survives the YAML round trip


def test_the_samples_are_there() -> None:
    assert {p.stem for p in FILES} >= {"rotor_example", "pedestals", "bearing_mass", "compressor", "conical_4"}


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_sample_imports_and_round_trips_through_yaml(path: Path, tmp_path: Path) -> None:
    result = import_ross(path)
    cfg = parse_config(result.rig)
    assert cfg.kind == "rotor" and cfg.rig_id == path.stem and cfg.ports is None
    text = result.to_yaml()
    out = tmp_path / "rig.yaml"
    out.write_text(text)
    assert load_config(out) == cfg
    header = text.split("\nschema:", 1)[0].splitlines()
    assert all(line.startswith("#") for line in header)
    assert str(path) in header[0] and "ROSS 2.3.0" in header[0]
    assert f"({len(result.not_carried)}):" in "\n".join(header)
    flat = " ".join(line[4:] for line in header)
    for item in result.not_carried:  # every sentence is in the header (wrapped)
        assert " ".join(item.split()) in " ".join(flat.split())
    # the lateral-only sentence, once
    assert sum("lateral only" in s for s in result.not_carried) == 1


def test_a_uniform_rotor_loses_only_its_axial_and_torsional_terms() -> None:
    result = import_ross(DATA / "rotor_example.toml")
    assert len(result.not_carried) == 1 and "lateral only" in result.not_carried[0]
    rig = result.rig
    assert rig["stations"] == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5], abs=1e-15)
    assert rig["shear_method"] == "cowper"
    assert rig["materials"] == {"steel": {"density": 7810.0, "youngs_modulus": 211e9, "shear_modulus": 81.2e9}}
    assert [d["station"] for d in rig["discs"]] == [3, 5]
    assert [(b["station"], b["kxx"], b["kyy"]) for b in rig["bearings"]] == [(1, 1e6, 0.8e6), (7, 1e6, 0.8e6)]
    assert rig["damping"] == {"kind": "none"}


# --------------------------------------------------------------------------------------------
# 2. the compressor: layers, mass, bearings and seals, spline resampling


def test_compressor_spans_and_layers(compressor: RossImport) -> None:
    shafts = _tables(_toml("compressor.toml"), "ShaftElement")
    assert len(shafts) == 91
    ns = Counter(t["n"] for t in shafts.values())
    rig = compressor.rig
    assert len(rig["stations"]) == len(ns) + 1
    assert len(rig["shaft"]) == len(shafts)
    starts = Counter(e["start"] for e in rig["shaft"])
    layered_ross = sum(c for c in ns.values() if c > 1)  # elements sharing their n with another
    layered_rig = sum(c for c in starts.values() if c > 1)
    assert layered_rig == layered_ross > 0
    assert {n + 1: c for n, c in ns.items()} == dict(starts)
    # node positions: the running sum of the span lengths (the first element of each n)
    lengths: dict[int, float] = {}
    for t in shafts.values():
        lengths.setdefault(t["n"], t["L"])
    assert rig["stations"] == pytest.approx(np.r_[0.0, np.cumsum([lengths[n] for n in sorted(lengths)])],
                                            rel=1e-15, abs=1e-15)
    # shaft_mat_1 and shaft_mat_3 are the same steel: one material; the 1 psi "sleeve" material another
    assert len(rig["materials"]) == len({(t["material"]["rho"], t["material"]["E"], t["material"]["G_s"])
                                          for t in shafts.values()}) == 2


def test_compressor_total_shaft_mass(compressor: RossImport) -> None:
    ross = 0.0
    for t in _tables(_toml("compressor.toml"), "ShaftElement").values():
        outer = t["odl"] ** 2 + t["odl"] * t["odr"] + t["odr"] ** 2
        inner = t["idl"] ** 2 + t["idl"] * t["idr"] + t["idr"] ** 2
        ross += t["material"]["rho"] * math.pi * t["L"] / 12.0 * (outer - inner)
    rig = compressor.rig
    mass = 0.0
    for e in rig["shaft"]:
        L = rig["stations"][e["end"] - 1] - rig["stations"][e["start"] - 1]
        do, di = e["outer_diameter"], e.get("inner_diameter", 0.0)
        dor, dir_ = e.get("outer_diameter_right", do), e.get("inner_diameter_right", di)
        rho = rig["materials"][e["material"]]["density"]
        mass += rho * math.pi * L / 12.0 * ((do**2 + do * dor + dor**2) - (di**2 + di * dir_ + dir_**2))
    assert mass == pytest.approx(ross, rel=1e-12)


def test_compressor_discs_bearings_and_seals_sit_on_their_nodes(compressor: RossImport) -> None:
    doc = _toml("compressor.toml")
    rig = compressor.rig
    discs = _tables(doc, "DiskElement")
    assert sorted(d["station"] for d in rig["discs"]) == sorted(t["n"] + 1 for t in discs.values())
    supports = _tables(doc, "BearingElement", "SealElement")
    assert len(supports) == 14
    assert sorted(b["station"] for b in rig["bearings"]) == sorted(t["n"] + 1 for t in supports.values())
    assert all("n_link" not in b for b in rig["bearings"])
    for table in supports:  # each speed table is reported, with its ROSS table name
        assert any(f'"{table}"' in s and "extrapolates" in s for s in compressor.not_carried)


def _written(entry: dict[str, Any], key: str) -> tuple[np.ndarray, np.ndarray]:
    v = entry[key]
    return np.asarray(v["speed_rpm"]), np.asarray(v["values"])


def test_compressor_tables_follow_ross_spline(compressor: RossImport) -> None:
    """At the saved speeds the written table is ROSS's spline (1e-12); between them the linear table
    stays within 1e-4 of the spline relative to the largest coefficient of the same matrix (K or C),
    and within 1e-3 relative to the coefficient's own largest value (measured: 4.8e-4, the
    cross-coupled damping of the tilting-pad bearings)."""
    by_station = {b["station"]: b for b in compressor.rig["bearings"]}
    worst_own = 0.0
    for table in _tables(_toml("compressor.toml"), "BearingElement", "SealElement").values():
        entry = by_station[table["n"] + 1]
        f = np.asarray(table["frequency"], dtype=float)
        fine = np.linspace(f[0], f[-1], 4001)
        for family in ("k", "c"):
            keys = [family + s for s in ("xx", "yy", "xy", "yx")]
            splines = {k: UnivariateSpline(f, np.asarray(table[k], dtype=float)) for k in keys}
            scale = max(np.abs(s(fine)).max() for s in splines.values())
            for k in keys:
                rpm, values = _written(entry, k)
                ref = splines[k](f)
                idx = np.abs(rpm[None, :] - (f * RAD_S_TO_RPM)[:, None]).argmin(axis=1)
                # the saved speeds, rounded to whole rpm within 1e-12 (418.8790204788 rad/s: 4000 rpm)
                assert rpm[idx] == pytest.approx(f * RAD_S_TO_RPM, rel=1e-12)
                own = np.abs(ref).max()
                assert np.abs(values[idx] - ref).max() <= 1e-12 * own, (k, table["tag"])
                assert rpm[0] == pytest.approx(f[0] * RAD_S_TO_RPM, rel=1e-12)
                assert rpm[-1] == pytest.approx(f[-1] * RAD_S_TO_RPM, rel=1e-12)
                even = np.linspace(f[0], f[-1], 65) * RAD_S_TO_RPM  # speed_points evenly spaced, all written
                assert np.abs(rpm[None, :] - even[:, None]).min(axis=1).max() <= 1e-9 * rpm[-1]
                exact = splines[k](fine)
                err = np.abs(np.interp(fine * RAD_S_TO_RPM, rpm, values) - exact).max()
                assert err <= 1e-4 * scale, (k, table["tag"], err / scale)
                worst_own = max(worst_own, err / np.abs(exact).max())
    assert worst_own <= 1e-3


def test_more_speed_points_follow_the_spline_closer() -> None:
    coarse, fine_ = import_ross(DATA / "compressor.toml", speed_points=9), import_ross(DATA / "compressor.toml",
                                                                                      speed_points=257)
    table = _tables(_toml("compressor.toml"), "BearingElement")["BearingElement_Bearing 0"]
    f = np.asarray(table["frequency"])
    spline = UnivariateSpline(f, np.asarray(table["cxy"]))
    x = np.linspace(f[0], f[-1], 3001)
    errs = []
    for result in (coarse, fine_):
        entry = next(b for b in result.rig["bearings"] if b["station"] == table["n"] + 1)
        rpm, values = _written(entry, "cxy")
        errs.append(np.abs(np.interp(x * RAD_S_TO_RPM, rpm, values) - spline(x)).max() / np.abs(spline(x)).max())
    assert errs[1] < 1e-4 < errs[0]


# --------------------------------------------------------------------------------------------
# 3. pedestals: ROSS's extra nodes become support nodes


def test_pedestals_become_support_nodes() -> None:
    rig = import_ross(DATA / "pedestals.toml").rig
    assert len(rig["stations"]) == 7
    links = sorted((b["station"], b["n_link"]) for b in rig["bearings"] if "n_link" in b)
    assert links == [(1, 8), (7, 9)]
    assert sorted(pm["station"] for pm in rig["point_masses"]) == [8, 9]
    assert all(pm["mass"] == 1.0 for pm in rig["point_masses"])
    grounded = sorted(b["station"] for b in rig["bearings"] if "n_link" not in b)
    assert grounded == [8, 9]
    assert parse_config(rig).n_support_nodes == 2


# --------------------------------------------------------------------------------------------
# 4. bad input names the file and the table.key


def _edited(tmp_path: Path, old: str, new: str, source: str = "rotor_example.toml", count: int = 1) -> Path:
    text = (DATA / source).read_text()
    assert old in text
    p = tmp_path / "rotor.toml"
    p.write_text(text.replace(old, new, count))
    return p


def test_a_file_that_is_not_toml(tmp_path: Path) -> None:
    p = tmp_path / "rotor.toml"
    p.write_text("this is = = not TOML\n")
    with pytest.raises(InputError) as exc:
        import_ross(p)
    assert exc.value.file == str(p) and exc.value.field == "" and "not TOML" in exc.value.message
    assert str(exc.value).startswith(f"{p}: not TOML")
    p.write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(InputError, match="not UTF-8"):
        import_ross(p)


def test_a_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError) as exc:
        import_ross(tmp_path / "nothing.toml")
    assert exc.value.file == str(tmp_path / "nothing.toml") and "not found" in exc.value.message


def test_toml_without_shaft_elements_is_no_ross_rotor(tmp_path: Path) -> None:
    p = tmp_path / "rotor.toml"
    p.write_text('ross_version = "2.3.0"\n\n["DiskElement_Disk 0"]\nn = 0\nm = 1.0\nId = 0.1\nIp = 0.2\n')
    with pytest.raises(InputError) as exc:
        import_ross(p)
    assert exc.value.file == str(p) and exc.value.field == "ShaftElement_*"
    assert "not" in exc.value.message.lower() or "no " in exc.value.message


@pytest.mark.parametrize(
    ("old", "new", "field", "message"),
    [
        ('odl = 0.05\nidr = 0.0\nodr = 0.05\nn = 3', 'odl = "0.05"\nidr = 0.0\nodr = 0.05\nn = 3',
         '"ShaftElement_Shaft Element 3".odl', "must be a number"),
        ("odl = 0.05\nidr = 0.0\nodr = 0.05\nn = 3", "odl = 0.05\nidr = 0.0\nodr = 0.05\nn = 3.5",
         '"ShaftElement_Shaft Element 3".n', "must be an integer"),
        ('shear_effects = true\nrotary_inertia = true\ngyroscopic = true\nshear_method_calc = "cowper"\n'
         'tag = "Shaft Element 1"', 'shear_effects = 1\nrotary_inertia = true\ngyroscopic = true\n'
         'shear_method_calc = "cowper"\ntag = "Shaft Element 1"', '"ShaftElement_Shaft Element 1".shear_effects',
         "true or false"),
        ('["ShaftElement_Shaft Element 2".material]\nname = "steel"\nrho = 7810.0',
         '["ShaftElement_Shaft Element 2".material]\nname = "steel"\nrho = "heavy"',
         '"ShaftElement_Shaft Element 2".material.rho', "must be a number"),
        ("kxx = [ 1000000.0,]\nkxy = [ 0,]\nkyx = [ 0,]\nkyy = [ 800000.0,]\nkzz = [ 0,]\nmxx = [ 0,]\nmxy = [ 0,]"
         "\nmyx = [ 0,]\nmyy = [ 0,]\nmzz = [ 0,]\nn = 6",
         "kxx = [ 1000000.0, 2e6,]\nkxy = [ 0,]\nkyx = [ 0,]\nkyy = [ 800000.0,]\nkzz = [ 0,]\nmxx = [ 0,]\n"
         "mxy = [ 0,]\nmyx = [ 0,]\nmyy = [ 0,]\nmzz = [ 0,]\nn = 6",
         '"BearingElement_Bearing 1".kxx', "2 values"),
        ("cxx = [ 0,]", 'cxx = [ "none",]', '"BearingElement_Bearing 0".cxx[0]', "must be a number"),
        ("idl = 0.0\nodl = 0.05\nidr = 0.0\nodr = 0.05\nn = 4", "idl = 0.06\nodl = 0.05\nidr = 0.0\nodr = 0.05\nn = 4",
         '"ShaftElement_Shaft Element 4".idl', "outer diameter"),
        ("n = 2\nm = 32.58972765304033", "n = 12\nm = 32.58972765304033", '"DiskElement_Disk 0".n', "node 12"),
    ],
    ids=["odl-string", "n-float", "flag-int", "rho-string", "bearing-length", "list-item", "bore", "disc-node"],
)
def test_wrong_fields_name_table_and_key(tmp_path: Path, old: str, new: str, field: str, message: str) -> None:
    p = _edited(tmp_path, old, new)
    with pytest.raises(InputError) as exc:
        import_ross(p)
    assert exc.value.file == str(p)
    assert exc.value.field == field
    assert message in exc.value.message
    assert str(exc.value).startswith(f"{p}: {field}: ")


def test_speed_points_must_be_two_or_more() -> None:
    with pytest.raises(InputError, match="speed_points"):
        import_ross(DATA / "rotor_example.toml", speed_points=1)


# --------------------------------------------------------------------------------------------
# what ROSS does that the rig states differently


def _ross_hutchinson(nu: float, r: float) -> float:
    """ROSS 2.3.0 shaft_element.py, shear_method_calc == "hutchinson" (mean diameter ratio r)."""
    r2 = r * r
    r12 = (1 + r2) ** 2
    return 6 * r12 * ((1 + nu) / (r12 * (7 + 12 * nu + 4 * nu**2) + 4 * r2 * (5 + 6 * nu + 2 * nu**2)))


def test_ross_hutchinson_elements_carry_the_coefficient_ross_uses(tmp_path: Path) -> None:
    p = _edited(tmp_path, 'shear_method_calc = "cowper"', 'shear_method_calc = "hutchinson"', "conical_4.toml", 4)
    result = import_ross(p)
    doc = tomllib.loads(p.read_text())
    tables = sorted(_tables(doc, "ShaftElement").values(), key=lambda t: t["n"])
    for t, e in zip(tables, result.rig["shaft"]):
        nu = t["material"]["E"] / (2 * t["material"]["G_s"]) - 1
        r = (t["idl"] + t["idr"]) / (t["odl"] + t["odr"])
        assert e["shear_coefficient"] == pytest.approx(_ross_hutchinson(nu, r), rel=1e-15)
        assert e["outer_diameter_right"] == t["odr"]
    assert _ross_hutchinson(0.3, 0.0) == pytest.approx(0.7116, abs=1e-4)  # not Hutchinson's 0.925
    assert any("hutchinson" in s and "1 + nu" in s for s in result.not_carried)
    parse_config(result.rig)


def test_element_proportional_damping(tmp_path: Path) -> None:
    # equal alpha, beta on every element: Rayleigh damping of the shaft elements
    p = _edited(tmp_path, "beta = 0.0", "beta = 2e-5", count=6)
    result = import_ross(p)
    assert result.rig["damping"] == {"kind": "rayleigh", "alpha": 0.0, "beta": 2e-5, "scope": "shaft_elements"}
    assert not any("proportional" in s for s in result.not_carried)
    # unequal values: not carried, and said so
    p = _edited(tmp_path, "beta = 0.0", "beta = 2e-5", count=2)
    result = import_ross(p)
    assert result.rig["damping"] == {"kind": "none"}
    assert any("proportional damping" in s and "Shaft Element 0" in s for s in result.not_carried)


_SEAL = """
["SealElement_Seal 0"]
cxx = [ 10.0, 20.0, 35.0, 40.0, 60.0,]
kxx = [ 1e5, 2e5, 2.5e5, 4e5, 6e5,]
kxy = [ 1e4, 2e4, 3e4, 4e4, 5e4,]
kyx = [ -1e4, -2e4, -3e4, -4e4, -5e4,]
frequency = [ 100.0, 200.0, 300.0, 400.0, 500.0,]
n = 0
tag = "Seal 0"
"""


def test_coincident_grounded_bearing_and_seal_are_summed(tmp_path: Path) -> None:
    p = tmp_path / "rotor.toml"
    p.write_text((DATA / "rotor_example.toml").read_text() + _SEAL)
    result = import_ross(p, rig_id="with_seal", speed_points=33)
    rig = result.rig
    assert rig["rig_id"] == "with_seal"
    at1 = [b for b in rig["bearings"] if b["station"] == 1]
    assert len(at1) == 1
    b = at1[0]
    seal = tomllib.loads(_SEAL)["SealElement_Seal 0"]
    f = np.asarray(seal["frequency"])
    # ROSS: kyy = kxx and cyy = cxx of the seal when not given; Bearing 0 has kxx 1e6, kyy 0.8e6
    expected = {"kxx": (1e6, "kxx"), "kyy": (0.8e6, "kxx"), "kxy": (0.0, "kxy"), "kyx": (0.0, "kyx"),
                "cxx": (0.0, "cxx"), "cyy": (0.0, "cxx")}
    for key, (constant, seal_key) in expected.items():
        rpm, values = _written(b, key)
        assert np.all(np.diff(rpm) > 0) and 33 <= rpm.size <= 33 + f.size
        idx = np.abs(rpm[None, :] - (f * RAD_S_TO_RPM)[:, None]).argmin(axis=1)
        ref = constant + UnivariateSpline(f, np.asarray(seal[seal_key], dtype=float))(f)
        assert values[idx] == pytest.approx(ref, rel=1e-12)
    assert any("summed" in s for s in result.not_carried)
    parse_config(rig)


_OTHERS = """
["MagneticBearingElement_AMB 0"]
n = 3
kxx = [ -2e5,]
cxx = [ 300.0,]
kp_pid = 1.5
tag = "AMB 0"

["GearElement_Gear 0"]
n = 1
m = 2.0
Id = 0.01
Ip = 0.02
pitch_diameter = 0.1

["CouplingElement_Coupling 0"]
n = 5
L = 0.25
m_l = 1.0
"""


def test_other_element_classes_are_carried_or_listed(tmp_path: Path) -> None:
    p = tmp_path / "rotor.toml"
    p.write_text((DATA / "rotor_example.toml").read_text() + _OTHERS)
    result = import_ross(p)
    notes = " ".join(result.not_carried)
    amb = next(b for b in result.rig["bearings"] if b["station"] == 4)
    assert (amb["kxx"], amb["kyy"], amb["cxx"], amb["cyy"]) == (-2e5, -2e5, 300.0, 300.0)
    assert '"MagneticBearingElement_AMB 0": a ROSS MagneticBearingElement, carried as the linear coefficients' in notes
    assert "kp_pid" in notes
    gear = next(d for d in result.rig["discs"] if d["station"] == 2)
    assert (gear["mass"], gear["transverse_inertia"], gear["polar_inertia"]) == (2.0, 0.01, 0.02)
    assert '"GearElement_Gear 0": a ROSS GearElement, carried as a rigid disc' in notes and "pitch_diameter" in notes
    assert '"CouplingElement_Coupling 0": ROSS element class CouplingElement has no counterpart' in notes
    parse_config(result.rig)


def test_a_coupling_alone_on_a_span_cannot_be_imported(tmp_path: Path) -> None:
    """A ROSS CouplingElement is a shaft element of its own span: without it the rotor would fall apart."""
    p = tmp_path / "rotor.toml"
    p.write_text((DATA / "rotor_example.toml").read_text().replace("ShaftElement_Shaft Element 5",
                                                                   "CouplingElement_Shaft Element 5"))
    with pytest.raises(InputError) as exc:
        import_ross(p)
    assert exc.value.field == '"CouplingElement_Shaft Element 5".n' and "span 5" in exc.value.message


def test_gaps_in_the_shaft_numbering_are_closed_and_reported(tmp_path: Path) -> None:
    text = (DATA / "bearing_mass.toml").read_text()
    for old, new in (("n = 1\naxial_force", "n = 4\naxial_force"),  # shaft element 1: n 1 -> 4
                     ("n = 2\nscale_factor", "n = 5\nscale_factor"),  # bearing 1 at its right node
                     ("n = 1\nm = ", "n = 4\nm = ")):  # the disc at its left node
        assert old in text
        text = text.replace(old, new)
    p = tmp_path / "rotor.toml"
    p.write_text(text)
    result = import_ross(p)
    assert [e["start"] for e in result.rig["shaft"]] == [1, 2]
    assert [d["station"] for d in result.rig["discs"]] == [2]
    assert sorted(b["station"] for b in result.rig["bearings"]) == [1, 3]
    assert any("do not run 0, 1, 2" in s for s in result.not_carried)


# --------------------------------------------------------------------------------------------
# 5. natural frequencies against ROSS 2.3.0

#: (reference key, ROSS file, speed rpm, relative tolerance). The compressor's seals and bearings depend
#: on speed: at 6000 and 9000 rpm the tilting-pad bearings' tables hold ROSS's spline exactly (both are
#: saved speeds) but "Seal 1" is saved at 2000, 4000, ..., 12000 rpm only, so at 9000 rpm its
#: coefficients come from the linear resampling (measured 1.4e-9 at 6000 rpm, 6.0e-8 at 9000 rpm).
CASES = [
    ("rotor_example_0rpm", "rotor_example", 0.0, 1e-9),
    ("rotor_example_4000rpm", "rotor_example", 4000.0, 1e-9),
    ("pedestals_0rpm", "pedestals", 0.0, 1e-9),
    ("pedestals_4000rpm", "pedestals", 4000.0, 1e-9),
    ("bearing_mass_0rpm", "bearing_mass", 0.0, 1e-9),
    ("axial_force_4000rpm", "axial_force", 4000.0, 1e-9),
    ("torque_4000rpm", "torque", 4000.0, 1e-9),
    ("conical_4_0rpm", "conical_4", 0.0, 3e-8),
    ("compressor_6000rpm", "compressor", 6000.0, 1e-8),
    ("compressor_9000rpm", "compressor", 9000.0, 3e-7),
]


@pytest.fixture(scope="module")
def reference() -> dict[str, Any]:
    return json.loads((DATA / "ross_reference.json").read_text())


@pytest.mark.parametrize(("key", "name", "rpm", "tol"), CASES, ids=[c[0] for c in CASES])
def test_natural_frequencies_match_ross(reference: dict[str, Any], key: str, name: str, rpm: float, tol: float) -> None:
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.modal import modes

    system = build_system(parse_config(import_ross(DATA / f"{name}.toml").rig))
    m = modes(system, rpm, n_modes=8)
    wd = np.asarray(reference[key]["wd"][:8])
    ours = 2 * np.pi * m.frequency_hz
    assert ours.size == wd.size == 8
    assert np.abs(ours / wd - 1).max() <= tol


# --------------------------------------------------------------------------------------------
# 6. issue 32: the model of ROSS's tests/data/rotor.toml (saved again by ROSS 2.3.0 as compressor.toml)


def test_compressor_model_critical_speed_search_does_not_raise(compressor: RossImport, reference: dict[str, Any]
                                                                ) -> None:
    """``rotorcheck model`` on ROSS's rotor.toml raised "f(a) and f(b) must have different signs": at
    1000-1250 rpm a branch of the 41-speed grid changes sides of the 1X and 2X lines but the mode of
    best MAC at the interval's ends does not (branches swap). Now: no exception, the interval is
    reported, the modes come back (against ROSS 2.3.0), and every critical speed found is one by its
    definition (a forward mode at that speed with f = order x speed, from modes() afresh)."""
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.modal import campbell, model_summary, modes

    # the bearing tables held outside their speeds, as the import wrote them before extrapolate: linear
    held = [{**b, "extrapolate": "hold"} if "extrapolate" in b else b for b in compressor.rig["bearings"]]
    config = parse_config({**compressor.rig, "bearings": held})
    system = build_system(config)
    speeds = np.linspace(0.0, config.analysis.campbell_max_rpm, 41)
    for order in (1, 2):
        camp = campbell(system, speeds, config.analysis.n_modes, order=order)
        assert any("between 1000 and 1250 rpm" in n and "no critical speed reported" in n for n in camp.notes)
        for rpm in camp.critical_speeds_rpm:
            md = modes(system, rpm, max_hz=1.5 * order * rpm / 60.0)
            fwd = md.frequency_hz[np.asarray(md.whirl) == "forward"]
            assert np.min(np.abs(fwd / (order * rpm / 60.0) - 1.0)) < 1e-6
    summary = model_summary(config, 6000.0, system)
    wd = 2 * np.pi * np.array([m["frequency_hz"] for m in summary["modes"]])
    assert np.abs(wd / np.asarray(reference["compressor_6000rpm"]["wd"][: wd.size]) - 1).max() <= 1e-8
    assert all(isinstance(w, str) for w in summary["warnings"])


def test_a_coaxial_rotor_is_refused_naming_the_file_and_field(tmp_path: Path) -> None:
    """ROSS's CoAxialRotor numbers its second shaft's first node one after the first shaft's last node
    (elements n = 0..2 end at node 3, the next shaft starts at node 4 with element n = 4). The import
    joined the two shafts into one (or, with a bearing on the first shaft's end node as in ROSS's
    CoAxialRotor example, said "node 10 is no node of the shaft"); now it refuses the rotor as coaxial."""
    text = (DATA / "rotor_example.toml").read_text()
    for k in (5, 4, 3):  # the last three elements become a second shaft, nodes 4..7
        old = f'["ShaftElement_Shaft Element {k}"]\nL = 0.25\nidl = 0.0\nodl = 0.05\nidr = 0.0\nodr = 0.05\nn = {k}\n'
        assert old in text
        text = text.replace(old, old.replace(f"n = {k}\n", f"n = {k + 1}\n"))
    text = text.replace("n = 6\n", "n = 7\n")  # bearing 1 at the end of the second shaft
    p = tmp_path / "coaxial.toml"
    p.write_text(text)
    with pytest.raises(InputError) as exc:
        import_ross(p)
    assert exc.value.file == str(p)
    assert exc.value.field == '"ShaftElement_Shaft Element 3".n'
    assert "coaxial" in exc.value.message and "not supported" in exc.value.message


def test_a_non_table_element_key_is_refused(tmp_path: Path) -> None:
    """``ShaftElement_x = 3`` at the top level was dropped without a word."""
    p = tmp_path / "rotor.toml"
    text = (DATA / "rotor_example.toml").read_text()
    p.write_text(text.replace("[parameters]", "ShaftElement_x = 3\n\n[parameters]"))
    with pytest.raises(InputError) as exc:
        import_ross(p)
    assert exc.value.file == str(p) and exc.value.field == "ShaftElement_x"
    assert "must be a table" in exc.value.message and "a number" in exc.value.message


def test_element_damping_with_alpha_is_carried_receptance_against_direct_assembly(tmp_path: Path) -> None:
    """ROSS's 6-DOF example (rotor_example, every shaft element alpha = 1 1/s, beta = 1e-5 s, bearings
    undamped): the import dropped element damping with alpha != 0 on a rotor with discs (receptance at
    the first resonance then off by orders of magnitude: no damping at all). Now ``scope:
    shaft_elements``; the receptance x -> x at the first disc against a direct solve of
    ``K - w^2 M + j w (C + Omega G)`` with C assembled here element by element from the closed-form
    uniform Timoshenko matrices (ROSS's ``sum alpha M_e + beta K_e``), at rest and at 3000 rpm."""
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.elements import beam_matrices
    from rotorcheck.fe.frf import receptance
    from rotorcheck.fe.shaft import cowper_shear_coefficient

    text = (DATA / "rotor_example.toml").read_text()
    assert text.count("alpha = 0.0") == text.count("beta = 0.0") == 6
    p = tmp_path / "rotor_6dof.toml"
    p.write_text(text.replace("alpha = 0.0", "alpha = 1.0").replace("beta = 0.0", "beta = 1e-05"))
    result = import_ross(p)
    assert result.rig["damping"] == {"kind": "rayleigh", "alpha": 1.0, "beta": 1e-5, "scope": "shaft_elements"}
    assert not any("proportional" in s for s in result.not_carried)
    system = build_system(parse_config(result.rig))
    doc = _toml("rotor_example.toml")
    shafts = sorted(_tables(doc, "ShaftElement").values(), key=lambda t: t["n"])
    L = np.array([t["L"] for t in shafts])
    mat = shafts[0]["material"]
    E, G, rho = mat["E"], mat["G_s"], mat["rho"]
    od, idm = np.array([t["odl"] for t in shafts]), np.array([t["idl"] for t in shafts])
    Me, _, Ke = beam_matrices(L, E, G, rho, od, idm, cowper_shear_coefficient(E / (2 * G) - 1, od, idm))
    n = system.n_dof
    C_shaft = np.zeros((n, n))
    for k in range(len(shafts)):
        dofs = np.r_[4 * k : 4 * k + 8]
        C_shaft[np.ix_(dofs, dofs)] += 1.0 * Me[k] + 1e-5 * Ke[k]
    o = system.dof(3, "x")
    for rpm in (0.0, 3000.0):
        M, _, Gm, K = system.matrices(rpm)
        # a grid and ROSS's first four damped frequencies (test_modal_6dof, rad/s), where damping rules
        f = np.r_[np.linspace(1.0, 200.0, 60), np.array([91.79647, 96.28891, 274.56591, 296.5005]) / (2 * np.pi)]
        H = receptance(system, f, rpm, o, o)[:, 0, 0]
        for fk, hk in zip(f, H):
            w = 2 * np.pi * fk
            Z = K - w**2 * M + 1j * w * (C_shaft + rpm * np.pi / 30 * Gm)
            ref = np.linalg.solve(Z, np.eye(n)[:, o])[o]
            assert abs(hk / ref - 1) <= 1e-8, (rpm, fk)


def test_speed_tables_extrapolate_as_ross_outside_the_saved_speeds(tmp_path: Path) -> None:
    """Issue 32: tables were held constant outside their speeds where ROSS extrapolates. A 2-speed
    bearing is ROSS's ``interp1d(frequency, values, kind=1, fill_value="extrapolate")`` (rebuilt here
    with scipy): the imported rig (``extrapolate: linear``) gives its values at 0 and 3x the top speed
    to round-off (held, the default: kxx 2x ROSS's at rest and 57 % below it at 1200 rad/s), and
    ``model`` says how the tables are extended."""
    from scipy.interpolate import interp1d

    from rotorcheck.fe.modal import model_summary

    text = (DATA / "rotor_example.toml").read_text()
    block = text[text.index('["BearingElement_Bearing 0"]'):text.index('["BearingElement_Bearing 1"]')]
    freq = [200.0, 400.0]  # rad/s
    values = {"kxx": [1.0e6, 1.5e6], "kyy": [0.8e6, 1.4e6], "cxx": [100.0, 300.0]}
    new = block.replace("kxx = [ 1000000.0,]", "kxx = [ 1000000.0, 1500000.0,]")
    new = new.replace("kyy = [ 800000.0,]", "kyy = [ 800000.0, 1400000.0,]")
    new = new.replace("cxx = [ 0,]", "cxx = [ 100.0, 300.0,]")
    new = new.replace("n = 0\n", "n = 0\nfrequency = [ 200.0, 400.0,]\n")
    p = tmp_path / "rotor.toml"
    p.write_text(text.replace(block, new))
    result = import_ross(p)
    entry = next(b for b in result.rig["bearings"] if b["station"] == 1)
    assert entry["extrapolate"] == "linear"
    config = parse_config(result.rig)
    bearing = next(b for b in config.bearings if b.station == 1)
    for speed in (0.0, 100.0, 300.0, 1200.0):  # rad/s: below, inside, above the saved speeds
        co = bearing.coefficients(speed * RAD_S_TO_RPM)
        for key, vals in values.items():
            ross = float(interp1d(freq, vals, kind=1, fill_value="extrapolate")(speed))
            assert co[key] == pytest.approx(ross, rel=1e-12, abs=1e-9), (key, speed)
    unset = [{k: v for k, v in b.items() if k != "extrapolate"} for b in result.rig["bearings"]]
    held = parse_config({**result.rig, "bearings": unset})  # the default: hold
    assert next(b for b in held.bearings if b.station == 1).coefficients(0.0)["kxx"] == 1.0e6
    assert next(b for b in held.bearings if b.station == 1).coefficients(1200.0 * RAD_S_TO_RPM)["kxx"] == 1.5e6
    assert any("linearly" in s and "extrapolat" in s for s in result.not_carried)
    warnings = model_summary(config, 0.0)["warnings"]
    assert any("bearings[0]" in w and "extrapolate: linear" in w for w in warnings)
    warnings = model_summary(held, 0.0)["warnings"]
    assert any("bearings[0]" in w and "extrapolate: hold" in w for w in warnings)


def test_compressor_at_rest_with_extrapolated_tables_is_close_to_ross(compressor: RossImport,
                                                                      reference: dict[str, Any]) -> None:
    """The compressor's bearing tables start at 3000 rpm (seals at 2000 rpm); at rest ROSS extrapolates
    its splines. Held at the 3000 rpm values the model had a spurious 2.5 rad/s mode and its lowest
    four modes 100 %, 1.3 %, 54 % and 0.06 % off ROSS 2.3.0's; extrapolated linearly (what the import
    writes) they are within 0.6 % (a line is not ROSS's cubic, so not closer)."""
    from rotorcheck.fe.assembly import build_system
    from rotorcheck.fe.modal import modes

    ross = np.asarray(reference["compressor_0rpm"]["wd"][:4])
    md = modes(build_system(parse_config(compressor.rig)), 0.0, max_hz=1.05 * ross[-1] / (2 * np.pi))
    wd = 2 * np.pi * md.frequency_hz
    assert wd.size == 4
    assert np.abs(wd / ross - 1).max() < 0.006

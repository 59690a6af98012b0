"""The CI regression of the design card: fit-noise, validate, detect through the command line on every bundled
case against the golden file (explicit `make golden` only). A file of its own (from test_pipeline.py): the
longest single test, so that xdist runs it beside the rest of the pipeline tests."""

from __future__ import annotations

import copy
import json

from tools import golden


def test_golden_regression() -> None:
    reference = json.loads(golden.GOLDEN.read_text())
    problems = golden.compare(golden.compute(), reference)
    assert not problems, "\n".join(problems[:20])


def test_golden_compare_catches_a_change() -> None:
    reference = json.loads(golden.GOLDEN.read_text())
    changed = copy.deepcopy(reference)
    changed["breathing_1000rpm_system"]["n_fault_points"] += 1
    changed["open_crack_0rpm_system"]["probe_damage_re"][0] *= 1 + 1e-3
    assert len(golden.compare(changed, reference)) == 2

"""Issue 32: every reader fuzzed (tools/fuzz_long.py, a fixed seed): each mutated input ends as a documented
refusal naming the file or as accepted output that passes the reader's check; nothing else (another
exception, a hang past 5 s, a crash) is allowed. A few inputs per reader here; tools/fuzz_long.py runs longer."""

from __future__ import annotations

from pathlib import Path

import pytest

from tools import fuzz_long

PER_READER = 40
TIMEOUT_S = 5.0


@pytest.fixture(scope="module")
def seeds(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[Path]]:
    return fuzz_long.make_seeds(tmp_path_factory.mktemp("seeds"))


@pytest.mark.parametrize("reader", list(fuzz_long.READERS))
def test_reader_fails_only_with_documented_errors(seeds: dict[str, list[Path]], tmp_path: Path, reader: str) -> None:
    for seed_file in seeds[reader]:  # the seeds themselves are accepted
        assert fuzz_long.classify(reader, seed_file) == ("accepted", ""), seed_file
    result = fuzz_long.Result()
    fuzz_long.run_reader(reader, seeds[reader], 0, PER_READER, 32, tmp_path, TIMEOUT_S, result)
    assert result.inputs == PER_READER
    assert result.others == []
    assert result.counts["refused"] > 0  # the mutations do reach the checks


def test_the_harness_counts_a_hang_and_a_crash(seeds: dict[str, list[Path]], tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """A harness that cannot fail is no test: a reader that hangs or dies is counted as 'other'."""
    import os
    import time

    def hang(path: Path) -> None:
        time.sleep(60)

    def die(path: Path) -> None:
        os._exit(9)

    def wrong(path: Path) -> int:
        raise KeyError("x")

    for fn, what in ((hang, "hang: more than 0.5 s"), (die, "crash"), (wrong, "KeyError")):
        monkeypatch.setitem(fuzz_long.READERS, "rig_yaml", fuzz_long.Reader(fn, lambda out: None, False))
        result = fuzz_long.Result()
        fuzz_long.run_reader("rig_yaml", seeds["rig_yaml"], 0, 2, 1, tmp_path, 0.5, result)
        assert result.inputs == 2 and result.counts["other"] == 2, (what, result)
        assert all(what in d for _, _, d in result.others), result.others

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


def _bounded(reader: str, path: Path, seconds: float = 10.0) -> tuple[str, str]:
    """fuzz_long.classify in a forked child, failing instead of hanging past ``seconds``."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(1) as pool:
        return pool.apply_async(fuzz_long.classify, (reader, path)).get(timeout=seconds)


def test_a_corrupt_global_heap_is_refused_not_looped_on(seeds: dict[str, list[Path]], tmp_path: Path) -> None:
    """Found by fuzzing: one flipped byte in an object's size in the global heap made libhdf5 loop forever
    reading the root's string attributes. The fuzzer's object was heap object 35, an 8-byte dimension-list
    reference, size 8 -> 1032; the netCDF labels (channel-name coordinates) renumbered the heap, so the first
    8-byte object (also a dimension-list reference) takes its place."""
    data = bytearray(seeds["sweep_hdf5"][0].read_bytes())
    gcol = data.find(b"GCOL")
    assert gcol > 0
    p = gcol + 16
    while int.from_bytes(data[p + 8:p + 16], "little") != 8:  # the first 8-byte heap object
        assert int.from_bytes(data[p:p + 2], "little") != 0, "no 8-byte object in the heap"
        p += 16 + (int.from_bytes(data[p + 8:p + 16], "little") + 7) // 8 * 8
    data[p + 9] ^= 0x04
    bad = tmp_path / "heap.h5"
    bad.write_bytes(bytes(data))
    outcome, detail = _bounded("sweep_hdf5", bad)
    assert outcome == "refused" and f"{bad}: byte {gcol}: corrupt HDF5 global heap" in detail


def test_a_string_pointing_past_the_heap_is_refused_fast(seeds: dict[str, list[Path]], tmp_path: Path) -> None:
    """Found by fuzzing: a variable-length string's heap address pointing past the file cost libhdf5 seconds."""
    import time

    import h5py

    bad = tmp_path / "vlen.h5"
    bad.write_bytes(seeds["sweep_hdf5"][0].read_bytes())
    with h5py.File(bad, "r") as h5:
        offset = h5["channels/name"].id.get_offset()
    data = bytearray(bad.read_bytes())
    data[offset + 4:offset + 12] = (2**62).to_bytes(8, "little")  # element 0's collection address
    bad.write_bytes(bytes(data))
    t0 = time.monotonic()
    outcome, detail = _bounded("sweep_hdf5", bad)
    assert outcome == "refused" and f"{bad}: /channels/name: corrupt string data: element 0 refers to no global " \
        "heap" in detail
    assert time.monotonic() - t0 < 3

"""A pytest plugin that records the CPU seconds of every test (issue 28: the suite's speed, measured as CPU
because the machine is shared and wall time follows its load).

``pytest -p tools.suite_cpu -n 2 ...`` writes one line per test, ``nodeid<TAB>cpu_s``, to
``$ROTORCHECK_SUITE_CPU`` (default ``suite_cpu.tsv``; each xdist worker appends): the process's CPU time
(user + system, :func:`time.process_time`) plus its children's (subprocesses, forked pools) over the test's
setup, call and teardown. ``python -m tools.suite_cpu [file]`` prints the files by CPU, largest first.
"""

from __future__ import annotations

import os
import resource
import sys
import time
from collections import defaultdict
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest


def _cpu() -> float:
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + kids.ru_utime + kids.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: Any) -> Generator[None, None, None]:
    start = _cpu()
    yield
    with open(os.environ.get("ROTORCHECK_SUITE_CPU", "suite_cpu.tsv"), "a") as fh:
        fh.write(f"{item.nodeid}\t{_cpu() - start:.3f}\n")


def main(path: str = "suite_cpu.tsv") -> None:
    by_file: dict[str, float] = defaultdict(float)
    total = 0.0
    for line in Path(path).read_text().splitlines():
        node, cpu = line.rsplit("\t", 1)
        by_file[node.split("::", 1)[0]] += float(cpu)
        total += float(cpu)
    print(f"total {total:.0f} CPU s over {len(by_file)} files")
    for name, cpu in sorted(by_file.items(), key=lambda kv: -kv[1])[:40]:
        print(f"{cpu:8.1f}  {name}")


if __name__ == "__main__":
    main(*sys.argv[1:])

"""The import graph: no module imports a module of a layer above it (issue 13).

Every import is counted, at module level or inside a function, so a function-level import cannot
hide a cycle. Within one package (``rotorcheck.fe``, ``rotorcheck.robust.mu``, ...) modules may
import each other; across packages only strictly lower layers.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "rotorcheck"

#: lowest first; a module's layer is that of its longest matching prefix
LAYERS: tuple[tuple[str, ...], ...] = (
    ("rotorcheck", "rotorcheck.errors", "rotorcheck.units", "rotorcheck.progress"),
    ("rotorcheck.fileio", "rotorcheck.resources", "rotorcheck.netcdf_view"),
    ("rotorcheck.safeload",),  # bounded YAML/TOML parsing over fileio's bounded reading; below config
    ("rotorcheck.config",),
    ("rotorcheck.variability",),  # benign parameter ranges over the config: above it, below fe/robust
    ("rotorcheck.fe", "rotorcheck.signal", "rotorcheck.robust"),  # numerics: FE, signal processing, robust
    ("rotorcheck.ross_import",),  # a ROSS rotor file as a rig document (its shear coefficient from fe)
    ("rotorcheck.faults", "rotorcheck.sweep"),
    ("rotorcheck.ingest",),  # time records in (issue 33): writes sweeps, below the simulators
    ("rotorcheck.sim",),  # simulators: above fe, faults and sweep
    ("rotorcheck.nominal",),
    ("rotorcheck.modal_anchor",),  # the healthy FRF's fitted modes moved by the model's sensitivities (issue 29)
    ("rotorcheck.sizing",),  # an element's loss from the measured pole shifts (issue 30's estimate interval)
    ("rotorcheck.signatures",),  # crack and benign change shapes by re-solving the model
    ("rotorcheck.rig",),  # a rig's assembled model at one speed as one object
    ("rotorcheck.updating",),  # model updating on the benign parameters
    ("rotorcheck.ranking",),  # candidate elements ranked by their best fits (one ranking: detect and locate)
    ("rotorcheck.location",),  # candidate elements with certified severity intervals
    ("rotorcheck.detectability",),  # what a rig, its sensors and noise can detect, per element
    ("rotorcheck.sensor_advice",),  # the sensor set that would locate a change not locatable (issue 30)
    ("rotorcheck.baseline", "rotorcheck.report"),
    ("rotorcheck.workflow",),
    ("rotorcheck.fleet",),  # many machines over time: tasks over the workflow, summary, trends (issue 15)
    ("rotorcheck.cli",),
    ("rotorcheck.__main__",),
)


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def layer_of(module: str) -> tuple[int, str]:
    """``(layer index, matching prefix)`` of a rotorcheck module."""
    best = (-1, "")
    for i, prefixes in enumerate(LAYERS):
        for p in prefixes:
            if (module == p or module.startswith(p + ".")) and len(p) > len(best[1]):
                best = (i, p)
    if best[0] < 0:
        raise AssertionError(f"{module} is in no layer: add it to LAYERS")
    return best


def _imports(path: Path, module: str) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text())
    out = []
    pkg = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")
                base = base[: len(base) - (node.level - 1)]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module or ""
            out.append((node.lineno, name))
            for a in node.names:  # "from rotorcheck import workflow" imports a module
                out.append((node.lineno, f"{name}.{a.name}"))
    return [(ln, n) for ln, n in out if n == "rotorcheck" or n.startswith("rotorcheck.")]


def _modules() -> list[Path]:
    return sorted(ROOT.rglob("*.py"))


def _exists(name: str) -> bool:
    p = ROOT.parent / Path(*name.split("."))
    return p.with_suffix(".py").exists() or (p / "__init__.py").exists()


def test_every_module_has_a_layer() -> None:
    for path in _modules():
        layer_of(_module_name(path))


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(ROOT.parent)))
def test_imports_go_only_downwards(path: Path) -> None:
    module = _module_name(path)
    mine, my_pkg = layer_of(module)
    bad = []
    for lineno, name in _imports(path, module):
        if not _exists(name):  # "from rotorcheck.x import name": the name is not a module
            continue
        theirs, their_pkg = layer_of(name)
        same_package = their_pkg == my_pkg and my_pkg != "rotorcheck"
        if theirs > mine or (theirs == mine and not same_package and name != "rotorcheck"):
            bad.append(f"line {lineno}: {name} (layer {theirs} {their_pkg}) from layer {mine} {my_pkg}")
    assert not bad, f"{module} imports upwards or sideways:\n" + "\n".join(bad)


def test_the_check_catches_an_upward_import(tmp_path: Path) -> None:
    """The rule itself: fe importing sweep, or sweep importing faults, would be reported."""
    assert layer_of("rotorcheck.fe.frf")[0] < layer_of("rotorcheck.sweep.format")[0]
    assert layer_of("rotorcheck.sweep.format")[0] == layer_of("rotorcheck.faults.crack")[0]
    assert layer_of("rotorcheck.sweep.format")[1] != layer_of("rotorcheck.faults.crack")[1]
    assert layer_of("rotorcheck.workflow")[0] < layer_of("rotorcheck.cli")[0]


def _graph() -> dict[str, set[str]]:
    """module -> the rotorcheck modules it imports (at module level or inside a function)."""
    graph: dict[str, set[str]] = {}
    for path in _modules():
        module = _module_name(path)
        graph[module] = {n for _, n in _imports(path, module) if _exists(n) and n != module and n != "rotorcheck"}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import loops of ``graph``: its strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_loop_anywhere() -> None:
    """Modules of one package may import each other (the layer rule allows it), but never in a loop: a loop
    is a module that cannot be read without the other (issue 28)."""
    loops = _cycles(_graph())
    assert not loops, "import loops:\n" + "\n".join(" <-> ".join(c) for c in loops)


def test_the_loop_check_finds_a_planted_loop() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


#: modules still over the size limit, to be split (issue 28): each entry is a shortfall, not a licence
OVERSIZE: set[str] = set()
#: lines a module may hold (issue 28: "no module over ~800 lines")
MAX_LINES = 800


def test_no_module_over_the_size_limit() -> None:
    """One concept per module: none over :data:`MAX_LINES` lines but the listed ones, and those listed are over
    it (an entry that no longer needs to be here is removed)."""
    sizes = {str(p.relative_to(ROOT.parent)): len(p.read_text().splitlines()) for p in _modules()}
    over = {name for name, n in sizes.items() if n > MAX_LINES}
    assert over <= OVERSIZE, f"over {MAX_LINES} lines: {sorted(over - OVERSIZE)}"
    assert OVERSIZE <= over, f"no longer over the limit, remove from OVERSIZE: {sorted(OVERSIZE - over)}"

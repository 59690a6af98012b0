"""Function-level imports only where a lazy import is documented as such (issue 28).

An import inside a function (or a method, a nested function, a lambda's body) is a lazy import: it must say
why on its line with a trailing ``# lazy: <why>`` comment (a statement over several lines: on its first line),
e.g. ``import matplotlib.pyplot as plt  # lazy: matplotlib only when plotting``. Everything else is imported at
module level. tests/test_layers.py counts both kinds for the layers and the loops.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "rotorcheck"

#: a lazy import's comment: ``# lazy:`` and a reason (anywhere in the line's comment, e.g. after another tool's)
LAZY_COMMENT = re.compile(r"(?:^|\s)#\s*lazy:\s*\S")

_SCOPES = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)


def _comments(source: str) -> dict[int, str]:
    """line number -> the comment on that line."""
    return {tok.start[0]: tok.string for tok in tokenize.generate_tokens(io.StringIO(source).readline)
            if tok.type == tokenize.COMMENT}


def function_imports(source: str) -> list[ast.Import | ast.ImportFrom]:
    """The import statements of ``source`` inside a function (at any depth)."""
    out: list[ast.Import | ast.ImportFrom] = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if in_function and isinstance(child, (ast.Import, ast.ImportFrom)):
                out.append(child)
            visit(child, in_function or isinstance(child, _SCOPES))

    visit(ast.parse(source), False)
    return out


def undocumented_lazy_imports(source: str, filename: str) -> list[str]:
    """``file:line: statement`` of every import inside a function whose (first) line carries no ``# lazy:``
    comment with a reason."""
    comments = _comments(source)
    lines = source.splitlines()
    return [f"{filename}:{node.lineno}: {lines[node.lineno - 1].strip()}" for node in function_imports(source)
            if not LAZY_COMMENT.search(comments.get(node.lineno, ""))]


def _modules() -> list[Path]:
    return sorted(ROOT.rglob("*.py"))


def test_every_function_level_import_is_a_documented_lazy_import() -> None:
    bad = []
    for path in _modules():
        bad += undocumented_lazy_imports(path.read_text(), str(path.relative_to(ROOT.parent)))
    assert not bad, ("imports inside a function without a '# lazy: <why>' comment (move them to module level, "
                     "or say why they wait):\n" + "\n".join(bad))


def test_the_package_has_lazy_imports_to_check() -> None:
    """The check reads the package (a wrong root would pass with nothing to check)."""
    assert len(_modules()) > 100
    assert sum(len(function_imports(p.read_text())) for p in _modules()) > 50


PLANTED = '''\
import os  # module level: no comment needed


def plain():
    import json
    return json


def documented():
    import json  # lazy: json only here
    return json


class Thing:
    def method(self):
        from collections import (  # lazy: the comment on the first line
            OrderedDict,
            deque,
        )
        return OrderedDict, deque

    async def later(self):
        def inner():
            import re  # lazy:
            return re
        import sys  # because
        return inner, sys


def too_late():
    from collections import (
        OrderedDict,  # lazy: not on the first line
    )
    return OrderedDict


def after_noqa():
    import this  # noqa: F401  # lazy: its reason after another tool's comment


square = lambda x: __import__("math").sqrt(x)  # noqa: E731 (a call, not an import statement)
'''


def test_the_check_reports_an_undocumented_function_level_import() -> None:
    lines = [line.strip() for line in PLANTED.splitlines()]
    expected = [f"planted.py:{lines.index(text) + 1}: {text}" for text in (
        "import json",  # plain: no comment (its first occurrence)
        "import re  # lazy:",  # no reason
        "import sys  # because",  # no "lazy:"
        "from collections import (",  # too_late: the comment on a later line of the statement
    )]
    assert undocumented_lazy_imports(PLANTED, "planted.py") == expected
    assert len(function_imports(PLANTED)) == 7  # not the module-level import, not the __import__ call


def test_the_check_accepts_a_documented_lazy_import() -> None:
    src = "def f():\n    import json  # lazy: json only when f runs\n    return json\n"
    assert undocumented_lazy_imports(src, "ok.py") == []
    assert undocumented_lazy_imports(src.replace("  # lazy: json only when f runs", ""), "bad.py") == [
        "bad.py:2: import json"]

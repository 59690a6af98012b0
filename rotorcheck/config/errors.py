"""Pydantic validation errors as a field path and a plain message (``bearings[1].kxx: must be > 0``)."""

from __future__ import annotations

from typing import Any

from pydantic import ValidationError


def field_path(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif str(part).startswith("function-") or part in ("SpeedTable", "float"):
            continue
        else:
            out += ("." if out else "") + str(part)
    return out


def _message(err: Any) -> str:
    t, ctx = err.get("type", ""), err.get("ctx") or {}
    if t == "greater_than":
        return f"must be > {ctx.get('gt')}"
    if t == "greater_than_equal":
        return f"must be >= {ctx.get('ge')}"
    if t == "less_than":
        return f"must be < {ctx.get('lt')}"
    if t == "less_than_equal":
        return f"must be <= {ctx.get('le')}"
    if t == "missing":
        return "required field is missing"
    if t == "extra_forbidden":
        return "unknown key"
    msg = str(err.get("msg", "invalid"))
    for prefix in ("Value error, ", "Assertion failed, "):
        if msg.startswith(prefix):
            msg = msg[len(prefix) :]
    return msg


def first_error(exc: ValidationError) -> tuple[str, str]:
    """The most specific error: prefer the deepest location (unions report every branch)."""
    errs = exc.errors()
    # for unions of float | SpeedTable, a unit error shows on the float branch: prefer that
    best = max(errs, key=lambda e: (e.get("type") != "model_type", len(e.get("loc", ()))))
    field = field_path(tuple(best.get("loc", ())))
    msg = _message(best)
    # a model-level validator message "name: text" refines the field path
    if ":" in msg and best.get("type") == "value_error":
        head, tail = msg.split(":", 1)
        if " " not in head.strip():
            field = f"{field}.{head.strip()}" if field else head.strip()
            msg = tail.strip()
    return field, msg

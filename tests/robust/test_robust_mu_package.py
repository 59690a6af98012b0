"""The robust.mu package as a package: reentrant (no module state; concurrent calls in threads give
exactly the sequential results), layered (each module imports only those below it, at module
level), and its public API."""

from __future__ import annotations

import ast
import importlib
import inspect
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from rotorcheck.robust import lft, mu

LAYERS = ["structure", "backends", "certificates", "witness", "driver"]


def cplx(rng: np.random.Generator, *shape: int) -> np.ndarray:
    return rng.normal(size=shape) + 1j * rng.normal(size=shape)


def siso_problem(seed: int, f: int) -> tuple[Any, ...]:
    """Additive SISO with general Me11 (the stacked first pass, near-cancellation points included)."""
    rng = np.random.default_rng(seed)
    G = cplx(rng, f) * 1e-7
    W = cplx(rng, f) * 10
    Zt = G * W * (1 + 0.5 * cplx(rng, f))
    me = lft.additive_me(G).copy()
    me[:, 0, 0] = 1e6 * cplx(rng, f)
    e = np.abs(Zt - G * W)
    V = e * rng.uniform(0.0, 1.0, f)
    V[: f // 5] = e[: f // 5] * (1 - 1e-4)  # near-cancellation: the per-point passes
    return me, W, Zt, V


def tall_problem(seed: int, f: int) -> tuple[Any, ...]:
    """Two outputs, one scalar uncertainty with Me11 != 0 (per-output noise blocks)."""
    rng = np.random.default_rng(seed)
    me = np.zeros((f, 3, 2), complex)
    me[:, 0, 0] = 0.3 * cplx(rng, f)
    me[:, 0, 1] = cplx(rng, f)
    me[:, 1:, 0] = cplx(rng, f, 2)
    me[:, 1:, 1] = cplx(rng, f, 2)
    W = cplx(rng, f)
    Zt = lft.lft_upper(me, 0.5 * cplx(rng, f)[:, None, None])[:, :, 0] * W[:, None]
    return me, W, Zt + 0.25 * cplx(rng, f, 2), 0.4


def assert_same(a: mu.GammaResult, b: mu.GammaResult) -> None:
    np.testing.assert_array_equal(a.status, b.status)
    np.testing.assert_array_equal(a.method, b.method)
    np.testing.assert_array_equal(a.reason, b.reason)
    np.testing.assert_array_equal(a.gamma_lower, b.gamma_lower)
    np.testing.assert_array_equal(a.gamma_upper, b.gamma_upper)
    assert a.n_solver_calls == b.n_solver_calls
    for da, db in zip(a.delta, b.delta, strict=True):
        assert (da is None) == (db is None)
        if da is not None and db is not None:
            for x, y in zip(da, db, strict=True):
                np.testing.assert_array_equal(x, y)


def test_concurrent_calls_in_threads_equal_sequential_runs() -> None:
    """Two different problems (SISO / two outputs, and the two backends) solved at the same time in
    two threads give exactly the results of solving them one after the other."""
    jobs = [(siso_problem(1, 120), {}), (tall_problem(2, 30), {}),
            (siso_problem(3, 40), {"backend": "cvxpy"}), (tall_problem(4, 12), {"backend": "cvxpy"})]
    sequential = [mu.required_gamma(*args, **kw) for args, kw in jobs]
    assert all(np.all(np.isin(r.status, ["ok", "unexplainable"])) for r in sequential)
    assert all(r.n_solver_calls > 0 for r in sequential)
    with ThreadPoolExecutor(max_workers=2) as pool:
        for _ in range(2):
            futures = [pool.submit(mu.required_gamma, *args, **kw) for args, kw in jobs]
            for fut, ref in zip(futures, sequential, strict=True):
                assert_same(fut.result(), ref)


def test_injected_failures_stay_in_their_context() -> None:
    """The testing hook is context-local: a call in another thread does not see it."""
    args = siso_problem(5, 10)
    with mu.inject_solver_failure([3]):
        here = mu.required_gamma(*args)
        with ThreadPoolExecutor(max_workers=1) as pool:
            there = pool.submit(mu.required_gamma, *args).result()
    assert here.status[3] == "solver_failed" and here.method[3] == "injected"
    assert there.status[3] != "solver_failed"


def test_a_cache_can_be_reused_across_calls() -> None:
    args = siso_problem(6, 20)
    cache = mu.LmiCache()
    a = mu.required_gamma(*args, cache=cache)
    n = len(cache)
    assert n >= 1
    b = mu.required_gamma(*args, cache=cache)
    assert len(cache) == n
    assert_same(a, b)
    assert_same(a, mu.required_gamma(*args))


def test_no_module_state() -> None:
    """No module of the package holds a mutable container (caches and buffers live in objects)."""
    for name in LAYERS:
        mod = importlib.import_module(f"rotorcheck.robust.mu.{name}")
        for key, val in vars(mod).items():
            if key.startswith("__") or inspect.ismodule(val):
                continue
            assert not isinstance(val, (dict, list, set, bytearray, np.ndarray)), f"{name}.{key}"


def test_layering_only_downward_module_level_imports() -> None:
    """structure <- backends <- certificates <- witness <- driver: each module imports only the
    modules before it, and only at module level (except cvxpy: the 'cvxpy' backend loads it on use,
    so that the default path never pays its ~0.8 s import; also under TYPE_CHECKING)."""
    for pos, name in enumerate(LAYERS):
        mod = importlib.import_module(f"rotorcheck.robust.mu.{name}")
        assert (mod.__doc__ or "").strip(), f"{name} has no docstring"
        tree = ast.parse(inspect.getsource(mod))
        top = set(map(id, tree.body))
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            lazy_heavy = isinstance(node, ast.Import) and [a.name for a in node.names] == ["cvxpy"]
            assert id(node) in top or lazy_heavy, f"{name}: import inside a function (line {node.lineno})"
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith(
                    "rotorcheck.robust.mu"):
                dep = (node.module or "").rsplit(".", 1)[-1]
                assert dep in LAYERS[:pos], f"{name} imports {dep}"


def test_public_api() -> None:
    for key in ("required_gamma", "required_gamma_bisection", "implicit_lmi_bound", "Structure",
                "Block", "GammaResult", "DEFAULT_BACKEND", "DEFAULT_TIME_LIMIT", "STATUS_OK",
                "STATUS_FAILED", "STATUS_UNEXPLAINABLE", "STATUS_LOWER_ONLY", "STATUS_BAD_DATA",
                "check_noise_bound", "inject_solver_failure", "ImplicitBound", "LmiCache"):
        assert key in mu.__all__ and hasattr(mu, key)
    assert mu.DEFAULT_BACKEND == "clarabel" and mu.DEFAULT_TIME_LIMIT == 10.0


def test_default_path_does_not_import_cvxpy() -> None:
    """Validation and detection with the default (Clarabel-direct) backend never load cvxpy."""
    import subprocess
    import sys

    code = ("import sys, numpy as np; from rotorcheck.robust.mu import required_gamma;"
            "me = np.array([[[0, 1], [1, 1e-6]]], complex);"
            "r = required_gamma(me, np.ones(1), np.array([2e-6 + 0j]), 1e-8);"
            "print('cvxpy' in sys.modules, r.status[0])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "ok"]

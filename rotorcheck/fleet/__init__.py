"""A fleet over time (issue 15): every new sweep of every machine against its baseline, in parallel, with a
summary table, an alert list, per-machine trends with a prognosis, and an HTML index (docs/fleet.md).

Modules: :mod:`~rotorcheck.fleet.layout` (where machines and sweeps are), :mod:`~rotorcheck.fleet.index`
(sha256 cache), :mod:`~rotorcheck.fleet.tasks` (one idempotent task per sweep),
:mod:`~rotorcheck.fleet.runner` (serial, processes, Dask), :mod:`~rotorcheck.fleet.summary` (table and
alerts), :mod:`~rotorcheck.fleet.changepoint` (the last change point of a series),
:mod:`~rotorcheck.fleet.trend` (the line since it and the crossing time), :mod:`~rotorcheck.fleet.html` (plots and
index.html), :mod:`~rotorcheck.fleet.command` (``rotorcheck fleet``).
"""

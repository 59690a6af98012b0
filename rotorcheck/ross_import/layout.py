"""ROSS nodes as rig stations: the shaft's spans (element numbers ``n``) and their positions, the extra
nodes after the shaft (pedestals) as support nodes, and the station of any node an element names.

ROSS node ``k`` becomes station ``k + 1``; numbering with gaps is closed up (and the import says so);
two-shaft (coaxial) rotors and spans holding no shaft element are refused."""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from rotorcheck.errors import InputError
from rotorcheck.ross_import.shaft import Shaft
from rotorcheck.ross_import.tables import Table, listing


@dataclass(frozen=True)
class Layout:
    """The rig's stations for a ROSS rotor.

    Attributes
    ----------
    span_ns : the shaft element numbers, ascending (one span each).
    stations : station positions, m (the running sum of the span lengths from 0).
    node_station : ROSS node -> rig station (1-based), shaft nodes then extra nodes.
    last_node : the ROSS node ending the shaft.
    point_mass_nodes : the ROSS node of each point mass, in the order given.
    notes : what was renumbered or approximated.
    """

    span_ns: list[int]
    stations: list[float]
    node_station: dict[int, int]
    last_node: int
    point_mass_nodes: list[int]
    notes: list[str]

    @property
    def n_spans(self) -> int:
        """Number of shaft spans (the rig's shaft stations are 1 .. n_spans + 1)."""
        return len(self.span_ns)

    def station_of(self, table: Table, key: str, node: int, shaft_only: bool = False) -> int:
        """The station of ROSS node ``node`` named by ``table.key``; ``shaft_only``: refuse an extra node."""
        st = self.node_station.get(node)
        if st is None:
            raise table.error(key, f"node {node} is no node of the shaft (nodes {self.span_ns[0]}..{self.last_node}) "
                              "or of a pedestal after it")
        if shaft_only and st > self.n_spans + 1:
            raise table.error(key, f"node {node} is an extra node (pedestal) after the shaft; ROSS places discs on "
                              "shaft nodes only")
        return st


def layout(
    source: str,
    shafts: Sequence[Shaft],
    span_like: Sequence[tuple[str, int]],
    bearing_nodes: Iterable[int],
    point_masses: Sequence[tuple[Table, str]],
) -> Layout:
    """The stations of a rotor whose ``shafts`` are sorted by ``(n, order)``.

    Parameters
    ----------
    source : the ROSS file (for errors).
    shafts : the shaft elements, sorted as ROSS sorts them (by ``n``, stably).
    span_like : ``(table path, n)`` of elements left out that occupy a span (couplings); refused if their
        span holds no shaft element.
    bearing_nodes : the nodes bearings and seals name (``n`` and ``n_link``).
    point_masses : ``(table, tag)`` of the point masses (their ``n`` is read here).
    """
    notes: list[str] = []
    span_ns = sorted({s.n for s in shafts})
    for tpath, n_span in span_like:
        if n_span not in span_ns:
            raise InputError(source, f"{tpath}.n", f"span {n_span} holds no ShaftElement, only this element, which a "
                             "rotorcheck rig cannot represent: replace it by a shaft element in ROSS and save again")
    n_spans = len(span_ns)
    first = {n: next(s for s in shafts if s.n == n) for n in span_ns}
    for left, right in itertools.pairwise(span_ns):
        if right == left + 2:  # ROSS's CoAxialRotor numbers the next shaft's first node one after the last one's end
            raise InputError(source, first[right].table.field("n"),
                             f"shaft element numbers jump from {left} to {right}: node {left + 1} ends one shaft and "
                             f"node {right} starts another, as ROSS numbers the shafts of a CoAxialRotor; coaxial "
                             "(two-shaft) rotors are not supported by rotorcheck (one shaft per rig)")
    stations = [0.0]
    for n in span_ns:
        stations.append(stations[-1] + first[n].L)
    for s in shafts:
        f = first[s.n]
        if s is not f and abs(s.L - f.L) > 1e-12 * f.L:
            notes.append(f"{s.table.path}: a layer of span n = {s.n} with L = {s.L:g} m, but the span is {f.L:g} m "
                         f"long ({f.table.path}, as ROSS places the nodes); carried on the span, with its length.")
    contiguous = span_ns == list(range(span_ns[0], span_ns[0] + n_spans))
    node_station: dict[int, int] = {n: i + 1 for i, n in enumerate(span_ns)}
    last_node = span_ns[-1] + 1
    node_station[last_node] = n_spans + 1
    if not contiguous or span_ns[0] != 0:
        notes.append(f"ROSS shaft element numbers n ({listing([str(n) for n in span_ns], 6)}) do not run 0, 1, 2, ... "
                     "without gaps (ROSS's own node positions and degrees of freedom disagree then): the spans are "
                     "joined in the order of n as stations 1, 2, ...")
    referenced: set[int] = set(bearing_nodes)
    pm_nodes: list[int] = []
    for table, _ in point_masses:
        node = table.integer("n")
        if node is None:
            raise table.error("n", "required field is missing")
        pm_nodes.append(node)
        referenced.add(node)
    extra_nodes = sorted(k for k in referenced if k > last_node)
    for j, k in enumerate(extra_nodes):
        node_station[k] = n_spans + 2 + j
    if extra_nodes and extra_nodes != list(range(last_node + 1, last_node + 1 + len(extra_nodes))):
        notes.append(f"ROSS extra nodes {listing([str(k) for k in extra_nodes], 6)} do not follow the last shaft node "
                     f"{last_node} without gaps: renumbered as support nodes {n_spans + 2}, {n_spans + 3}, ...")
    return Layout(span_ns=span_ns, stations=stations, node_station=node_station, last_node=last_node,
                  point_mass_nodes=pm_nodes, notes=notes)

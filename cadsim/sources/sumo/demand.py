"""Random demand drawn in this process: ``[traffic.demand]`` → route files, no subprocess.

What randomTrips + duarouter did per episode (≈ 1.2 core-seconds: three Python interpreters and a
router), done once per network and process for the part that does not depend on the seed, and in
milliseconds per episode for the part that does:

- once per (network, vtypes file) in a process (:func:`demand_plan`, cached): the fringe edges
  where trips start (no incoming connection) and end (no outgoing one), per vehicle class, and
  the fastest route between every start and end edge (sumolib's Dijkstra, as duarouter's
  default); start/end pairs without a route (a U-turn where U-turns are disabled) are left out,
  as randomTrips' ``--validate`` dropped them;
- per episode (:func:`write_demand`): departures every ``period`` seconds from 0 until ``end``
  (randomTrips' ``-p``), each a start edge drawn uniformly among those with a route and an end
  edge uniformly among the ends reachable from it, and a concrete vType drawn from the
  distribution by its probabilities (duarouter did this); pedestrians walk between a start and
  an end edge that allow pedestrians, routed by sumo at departure.

Every draw comes from demand model :data:`DEMAND_MODEL`'s stream of the episode's simulation seed
(``SeedSequence(sim seed, spawn_key=(9, kind))``, kind 0 vehicles, 1 bicycles, 2 persons) through
integer draws and comparisons of sums of the file's probabilities: the same files on every CPU.
"""

from __future__ import annotations

import hashlib
import threading
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import sumolib

from cadsim.sources.sumo.build import ToolFailed
from cadsim.sources.sumo.xml_files import check_size, parse_xml

DEMAND_MODEL = 1
"""Version of the in-process demand draw; a SUMO dataset's manifest states it (``generation.demand``)."""
DEMAND_STREAM = 9
KINDS = ("vehicle", "bicycle", "person")
# SUMO's built-in types and their vehicle classes.
BUILTIN_CLASSES = {
    "DEFAULT_VEHTYPE": "passenger",
    "DEFAULT_PEDTYPE": "pedestrian",
    "DEFAULT_BIKETYPE": "bicycle",
    "DEFAULT_CONTAINERTYPE": "ignoring",
}


@dataclass(frozen=True)
class Demand:
    """Files of generated demand: route files for sumo ``-r`` and additional files (vTypes that
    route files refer to but do not contain) for sumo ``-a``."""

    routes: list[Path]
    additional: list[Path]


@dataclass(frozen=True)
class TypeChoice:
    """A vType or vTypeDistribution resolved to its concrete member types, their cumulative
    probabilities (ascending, last = total) and their vehicle classes."""

    ids: tuple[str, ...]
    cumulative: tuple[float, ...]
    classes: tuple[str, ...]

    def draw(self, u: np.ndarray) -> np.ndarray:
        """Member indices for uniform draws ``u`` in [0, 1)."""
        cum = np.asarray(self.cumulative)
        return np.minimum(np.searchsorted(cum, u * cum[-1], side="right"), len(cum) - 1)


@dataclass(frozen=True)
class Routes:
    """For one vehicle class: start edges that reach at least one end edge, and per start edge
    its reachable end edges with the route (edge ids, space-separated) to each."""

    starts: tuple[str, ...]
    ends: dict[str, tuple[str, ...]]
    edges: dict[tuple[str, str], str]


def read_types(vtypes: Path) -> dict[str, TypeChoice]:
    """Every vType and vTypeDistribution of ``vtypes`` (and SUMO's built-in types)."""
    root = parse_xml(vtypes).getroot()
    vclass = dict(BUILTIN_CLASSES)
    prob: dict[str, float] = {}
    for e in root.iter("vType"):
        vclass[e.get("id")] = e.get("vClass", "passenger")
        prob[e.get("id")] = float(e.get("probability", 1.0))
    out = {t: TypeChoice((t,), (1.0,), (c,)) for t, c in vclass.items()}
    for dist in root.iter("vTypeDistribution"):
        members = [(c.get("id"), prob[c.get("id")]) for c in dist if c.tag == "vType"]
        refs = (dist.get("vTypes") or "").split()
        weights = (dist.get("probabilities") or "").split()
        members += [(r, float(weights[k]) if weights else prob.get(r, 1.0)) for k, r in enumerate(refs)]  # fmt: skip
        if not members:
            continue
        ids = tuple(m for m, _ in members)
        out[dist.get("id")] = TypeChoice(
            ids, tuple(np.cumsum([w for _, w in members]).tolist()), tuple(vclass[m] for m in ids)
        )
    return out


class DemandPlan:
    """What the demand of one network and vtypes file needs, whatever the seed (module
    docstring): the types, and routes per vehicle class (computed on first use)."""

    def __init__(self, net: Path, vtypes: Path) -> None:
        check_size(Path(net))
        self.net = sumolib.net.readNet(str(net), withInternal=False)
        self.types = read_types(Path(vtypes))
        self._routes: dict[str, Routes] = {}

    def _fringe(self, vclass: str) -> tuple[list, list]:
        edges = [
            e
            for e in self.net.getEdges(withInternal=False)
            if e.getFunction() == "" and e.allows(vclass)
        ]
        starts = sorted((e for e in edges if not e.getIncoming()), key=lambda e: e.getID())
        ends = sorted((e for e in edges if not e.getOutgoing()), key=lambda e: e.getID())
        return starts, ends

    def routes(self, vclass: str) -> Routes:
        """Start edges, reachable ends and routes for ``vclass`` (fastest path, as duarouter)."""
        if vclass not in self._routes:
            starts, ends = self._fringe(vclass)
            reach: dict[str, tuple[str, ...]] = {}
            edges: dict[tuple[str, str], str] = {}
            for s in starts:
                found = []
                for t in ends:
                    path, _ = self.net.getFastestPath(s, t, vClass=vclass)
                    if path:
                        found.append(t.getID())
                        edges[(s.getID(), t.getID())] = " ".join(e.getID() for e in path)
                if found:
                    reach[s.getID()] = tuple(found)
            self._routes[vclass] = Routes(tuple(reach), reach, edges)
        return self._routes[vclass]

    def walks(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """(start edges, end edges) of pedestrians (sumo routes the walks)."""
        starts, ends = self._fringe("pedestrian")
        return tuple(e.getID() for e in starts), tuple(e.getID() for e in ends)


_plans: dict[tuple[str, str], DemandPlan] = {}  # per process: (net sha256, vtypes sha256) -> plan
_plans_lock = threading.Lock()


def demand_plan(net: Path, vtypes: Path) -> DemandPlan:
    """The cached :class:`DemandPlan` of these files' contents (one per process)."""
    key = tuple(hashlib.sha256(Path(p).read_bytes()).hexdigest() for p in (net, vtypes))
    with _plans_lock:
        if key not in _plans:
            _plans[key] = DemandPlan(net, vtypes)
        return _plans[key]


def departures(period: float, end: float) -> np.ndarray:
    """Departure times 0, period, 2·period, … below ``end`` (seconds; randomTrips' ``-p``)."""
    if period <= 0:
        return np.zeros(0)
    return np.arange(int(np.ceil(end / period - 1e-9))) * float(period)


def _rng(seed: int, kind: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(DEMAND_STREAM, kind)))


def _vehicles(plan: DemandPlan, demand: dict, kind: int, seed: int) -> str:
    """The route file of vehicles (kind 0) or bicycles (kind 1)."""
    name = KINDS[kind]
    choice = plan.types[demand[f"{name}_type"]]
    times = departures(demand[f"{name}_period"], demand["end"])
    rng = _rng(seed, kind)
    member = choice.draw(rng.random(len(times)))
    first, second = rng.random(len(times)), rng.random(len(times))
    prefix = "veh" if kind == 0 else "bike"
    extra = ' departSpeed="max"' if kind == 0 else ""
    lines = ["<routes>"]
    for k, t in enumerate(times):
        vtype, vclass = choice.ids[member[k]], choice.classes[member[k]]
        routes = plan.routes(vclass)
        if not routes.starts:
            raise ToolFailed(
                f"{demand[f'{name}_type']}: no route between two fringe edges for vClass {vclass}"
            )
        start = routes.starts[int(first[k] * len(routes.starts))]
        ends = routes.ends[start]
        route = routes.edges[(start, ends[int(second[k] * len(ends))])]
        lines.append(
            f'    <vehicle id="{prefix}{k}" type={quoteattr(vtype)} depart="{t:.2f}" '
            f'departLane="best"{extra}><route edges={quoteattr(route)}/></vehicle>'
        )
    return "\n".join([*lines, "</routes>", ""])


def _persons(plan: DemandPlan, demand: dict, seed: int) -> str:
    starts, ends = plan.walks()
    times = departures(demand["person_period"], demand["end"])
    if len(times) and not (starts and ends):
        raise ToolFailed("no fringe edges where pedestrians may walk")
    rng = _rng(seed, 2)
    first, second = rng.random(len(times)), rng.random(len(times))
    lines = ["<routes>"]
    for k, t in enumerate(times):
        start, end = starts[int(first[k] * len(starts))], ends[int(second[k] * len(ends))]
        lines.append(
            f'    <person id="ped{k}" depart="{t:.2f}" type={quoteattr(demand["person_type"])}>'
            f"<walk from={quoteattr(start)} to={quoteattr(end)}/></person>"
        )
    return "\n".join([*lines, "</routes>", ""])


def write_demand(net: Path, demand: dict, seed: int, folder: Path) -> Demand:
    """Draw episode ``seed``'s demand (module docstring) and write its route files into
    ``folder`` (the simulation's own run folder); the vtypes file is loaded as an additional."""
    plan = demand_plan(Path(net), Path(demand["vtypes"]))
    folder = Path(folder) / "demand"
    folder.mkdir(parents=True, exist_ok=True)
    routes = []
    files = {"vehicles": lambda: _vehicles(plan, demand, 0, seed)}
    if demand["bicycle_period"] > 0:
        files["bicycles"] = lambda: _vehicles(plan, demand, 1, seed)
    if demand["person_period"] > 0:
        files["persons"] = lambda: _persons(plan, demand, seed)
    for name, text in files.items():
        path = folder / f"{name}.rou.xml"
        path.write_text(text(), encoding="utf-8")
        routes.append(path)
    return Demand(routes=routes, additional=[Path(demand["vtypes"]).resolve()])

"""Mechanisms described in TOML: serial chains from DH tables, coupled into a
translational parallel mechanism (thesis ch. 4-5), without writing Python.

The format (docs/spec.md has the full reference and an example)::

    name = "thesis_sim"
    gravity = [0.0, 0.0, 0.0]        # [m/s2], world frame N_0

    [platform]                       # omit for a single serial chain
    mass = 0.0                       # m of (5.7) [kg]
    independent = ["x", "y"]         # q# of (5.52): which platform coordinates
    start = [0.07, 0.17, 0.0]        # default start point [m]

    [[chains]]
    base = [0.05, 0.0, 0.0]          # o_i [m]
    rotation = [[1,0,0],[0,1,0],[0,0,1]]   # E_i = [1]_{N_0|N_i} (5.13)
    attach = [0.0, 0.0, 0.0]         # x_i: where the chain holds the platform, in B_0

    [[chains.links]]                 # one DH row (4.1) and the link it moves
    name = "q1"
    joint = "R"                      # "R" or "P"
    a = 0.12                         # DH a [m], alpha [rad], d [m], theta [rad]
    mass = 0.143
    com = [-0.06, 0.0, 0.0]          # in the link's DH frame (at its distal joint)
    inertia = [0.0, 1.716e-4, 1.716e-4]   # about the com: diagonal or 3x3
    rotor_inertia = 0.0              # J_r (4.139) [kg m2]
    actuated = true
    mode = 0.865                     # this joint in the working mode at the reference pose

    [[chains.links.point_masses]]    # seed 001 (55): counter-mass or payload
    mass = 0.2
    at = [-0.2, 0.0, 0.0]            # in the link's DH frame [m]

The architecture matrices follow from the chains: ``D`` stacks identities
(translational platform, 5.19), ``d_i = o_i - x_i`` (5.12), ``E`` is block
diagonal of the ``E_i`` (5.13) and ``F = 0`` (no affine constraints, 5.22).
The working mode is given by the joints' ``mode`` values: the configuration
for another platform position is found by continuation from there
(:func:`plant.specsim.assemble`).

Every semantic error is a :class:`SpecError` naming the file, the line when it
can be found, the key path and the value; TOML syntax errors keep tomllib's line.
"""
from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .parallel import ParallelMechanism
from .serial import PRISMATIC, REVOLUTE, DHJoint, RigidLink, SerialChain, with_point_mass

#: The shipped specs (package data).
SPEC_DIR = Path(__file__).resolve().parent / "specs"
#: Platform coordinates, in the order of q_0 (5.5).
AXES = ("x", "y", "z")

_TOP_KEYS = {"name", "description", "gravity", "platform", "chains"}
_PLATFORM_KEYS = {"mass", "independent", "start"}
_CHAIN_KEYS = {"name", "base", "rotation", "attach", "links"}
_LINK_KEYS = {"name", "joint", "a", "alpha", "d", "theta", "mass", "com", "inertia", "rotor_inertia",
              "gear_ratio", "actuated", "mode", "point_masses", "input"}
_POINT_KEYS = {"mass", "at"}


class SpecError(ValueError):
    """A mechanism description that cannot be used.

    Attributes
    ----------
    source : str
        The file (or "<string>").
    key : str
        Dotted key path, e.g. ``chains[1].links[0].mass`` (empty for syntax errors).
    value : object
        The offending value.
    line : int or None
        1-based line in the file, when found.
    """

    def __init__(self, source: str, key: str, value, why: str, line: int | None = None):
        self.source, self.key, self.value, self.line = source, key, value, line
        where = f"{source}, line {line}" if line else source
        super().__init__(f"{where}: {key} = {value!r}: {why}" if key else f"{where}: {why}")


@dataclass(frozen=True)
class JointInfo:
    """Name, actuation and working-mode value of one joint of a chain."""

    name: str
    actuated: bool
    mode: float
    input: str   # the torque input's name when actuated ("" otherwise)


@dataclass(frozen=True)
class ChainSpec:
    """One serial chain placed in the world."""

    name: str
    chain: SerialChain
    joints: tuple        # of JointInfo
    base: tuple          # o_i [m]
    rotation: tuple      # E_i, 3x3
    attach: tuple        # x_i in B_0 [m]


@dataclass(frozen=True)
class PlantSpec:
    """A mechanism description: one serial chain, or chains coupled to a translational platform.

    ``mechanism`` (parallel only) is the :class:`~plant.parallel.ParallelMechanism` of ch. 5.
    """

    name: str
    description: str
    gravity: tuple
    chains: tuple                 # of ChainSpec
    platform_mass: float | None   # None: a serial chain (no [platform])
    independent: tuple = ()       # indices into q_0 (0, 1, 2)
    start: tuple = ()
    source: str = "<string>"
    text: str = ""                # the TOML, to embed in an FMU

    @property
    def is_parallel(self) -> bool:
        return self.platform_mass is not None

    @property
    def mechanism(self) -> ParallelMechanism:
        if not self.is_parallel:
            raise ValueError(f"{self.source}: a serial chain (no [platform]) has no parallel mechanism")
        n = len(self.chains)
        d = np.concatenate([np.subtract(c.base, c.attach) for c in self.chains])      # (5.12)
        D = np.vstack([np.eye(3)] * n)                                                  # (5.19)
        E = np.zeros((3 * n, 3 * n))                                                    # (5.13)
        for i, c in enumerate(self.chains):
            E[3 * i:3 * i + 3, 3 * i:3 * i + 3] = c.rotation
        F = np.zeros((3 * n, sum(c.chain.dof for c in self.chains)))                    # (5.22)
        return ParallelMechanism(
            chains=tuple(c.chain for c in self.chains), platform_mass=self.platform_mass,
            d=d, D=D, E=E, F=F, independent=self.independent, actuated=self.actuated_indices,
            gravity=np.asarray(self.gravity, dtype=float))

    def joints(self):
        """(index in q, chain number, JointInfo) for every joint; q = [q_0, q_1, ...] when
        parallel, the chain's joints alone when serial."""
        k = 3 if self.is_parallel else 0
        out = []
        for i, c in enumerate(self.chains):
            for info in c.joints:
                out.append((k, i, info))
                k += 1
        return out

    @property
    def actuated_indices(self) -> tuple:
        return tuple(k for k, _, info in self.joints() if info.actuated)

    @property
    def inputs(self) -> tuple:
        """The torque inputs' names, in the order of :attr:`actuated_indices`."""
        return tuple(info.input for _, _, info in self.joints() if info.actuated)


def spec_path(name_or_path) -> Path:
    """A shipped spec's name (``"bench_5r"``) or a path to a ``.toml`` file."""
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        return p
    shipped = SPEC_DIR / f"{p.name}.toml"
    if shipped.exists():
        return shipped
    raise FileNotFoundError(f"no spec file {str(name_or_path)!r} and no shipped spec of that name "
                            f"(shipped: {', '.join(shipped_specs())})")


def shipped_specs() -> list[str]:
    return sorted(p.stem for p in SPEC_DIR.glob("*.toml"))


def load(path) -> PlantSpec:
    """Read and check a mechanism description (a path or a shipped spec's name)."""
    path = spec_path(path)
    return loads(path.read_text(encoding="utf-8"), source=str(path))


def loads(text: str, source: str = "<string>") -> PlantSpec:
    """Parse and check a mechanism description given as TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SpecError(source, "", None, f"TOML syntax: {exc}", _syntax_line(exc)) from None
    return _Reader(text, source).spec(data)


def _syntax_line(exc) -> int | None:
    """The line of a TOML syntax error: ``exc.lineno`` (Python 3.14's tomllib), else read from
    tomllib's message, the only place Python 3.11-3.13 give it (a third party's text, not ours)."""
    if getattr(exc, "lineno", None) is not None:
        return exc.lineno
    m = re.search(r"line (\d+)", str(exc))
    return int(m.group(1)) if m else None


class _Reader:
    """Checks the parsed TOML, raising :class:`SpecError` with the line of the key."""

    def __init__(self, text: str, source: str):
        self.lines = text.splitlines()
        self.text = text
        self.source = source

    # --- errors --------------------------------------------------------------------------
    def fail(self, path: tuple, value, why: str):
        raise SpecError(self.source, _dotted(path), value, why, _find_line(self.lines, path))

    def known(self, table: dict, allowed: set, path: tuple):
        for key in table:
            if key not in allowed:
                self.fail(path + (key,), table[key], f"unknown key; valid: {', '.join(sorted(allowed))}")

    # --- values --------------------------------------------------------------------------
    def number(self, table, key, path, default=None, minimum=None, positive=False):
        if key not in table:
            if default is None:
                self.fail(path + (key,), None, "missing (required)")
            return float(default)
        value = table[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(path + (key,), value, "must be a finite number")
        if positive and value <= 0.0:
            self.fail(path + (key,), value, "must be > 0")
        if minimum is not None and value < minimum:
            self.fail(path + (key,), value, f"must be >= {minimum:g}")
        return float(value)

    def vector(self, table, key, path, default=None, n=3):
        if key not in table:
            if default is None:
                self.fail(path + (key,), None, "missing (required)")
            return tuple(default)
        value = table[key]
        if not (isinstance(value, list) and len(value) == n):
            self.fail(path + (key,), value, f"must be a list of {n} numbers")
        return tuple(self.number({key: v}, key, path) for v in value)

    def matrix(self, table, key, path, default):
        value = table.get(key, default)
        if not (isinstance(value, list) and len(value) == 3 and all(isinstance(r, list) and len(r) == 3
                                                                      for r in value)):
            self.fail(path + (key,), value, "must be a 3x3 list of lists")
        return np.array([[self.number({key: v}, key, path) for v in row] for row in value])

    # --- tables --------------------------------------------------------------------------
    def spec(self, data: dict) -> PlantSpec:
        self.known(data, _TOP_KEYS, ())
        name = data.get("name", Path(self.source).stem)
        if not isinstance(name, str):
            self.fail(("name",), name, "must be a string")
        gravity = self.vector(data, "gravity", (), default=(0.0, 0.0, 0.0))
        chains_data = data.get("chains")
        if not (isinstance(chains_data, list) and chains_data):
            self.fail(("chains",), chains_data, "need at least one [[chains]] table")
        chains = tuple(self.chain(c, ("chains", i)) for i, c in enumerate(chains_data))
        seen = set()
        for i, c in enumerate(chains):
            for j, info in enumerate(c.joints):
                if info.name in seen:
                    self.fail(("chains", i, "links", j, "name"), info.name, "joint names must be unique")
                seen.add(info.name)
        inputs = [info.input for c in chains for info in c.joints if info.actuated]
        taken = seen | {"x", "y", "z", "dx", "dy", "dz", "residual", "error"} | {f"d{n}" for n in seen}
        for i, c in enumerate(chains):
            for j, info in enumerate(c.joints):
                if info.actuated and info.input in taken:
                    self.fail(("chains", i, "links", j, "input"), info.input,
                              "the torque input's name is taken (by another input or an output)")
                taken.add(info.input)
        if not inputs:
            self.fail(("chains",), "...", "no joint is actuated (set actuated = true on at least one link)")
        common = dict(name=name, description=str(data.get("description", "")), gravity=gravity, chains=chains,
                      source=self.source, text=self.text)
        if "platform" not in data:
            if len(chains) != 1:
                self.fail(("platform",), None, f"{len(chains)} chains need a [platform] to couple them")
            return PlantSpec(platform_mass=None, **common)
        return self.platform(data["platform"], common)

    def platform(self, table, common) -> PlantSpec:
        path = ("platform",)
        if not isinstance(table, dict):
            self.fail(path, table, "must be a table")
        self.known(table, _PLATFORM_KEYS, path)
        mass = self.number(table, "mass", path, default=0.0, minimum=0.0)
        independent = table.get("independent", list(AXES))
        if not (isinstance(independent, list) and independent and all(a in AXES for a in independent)
                and len(set(independent)) == len(independent)):
            self.fail(path + ("independent",), independent, f"must be distinct names among {list(AXES)}")
        start = self.vector(table, "start", path, default=(0.0, 0.0, 0.0))
        spec = PlantSpec(platform_mass=mass, independent=tuple(AXES.index(a) for a in independent),
                         start=start, **common)
        if len(spec.actuated_indices) != len(spec.independent):
            self.fail(path + ("independent",), independent,
                      f"{len(spec.independent)} degrees of freedom but {len(spec.actuated_indices)} actuated "
                      f"joints ({', '.join(spec.inputs)}): the inverse dynamics (5.74) need as many")
        return spec

    def chain(self, table, path) -> ChainSpec:
        if not isinstance(table, dict):
            self.fail(path, table, "must be a table")
        self.known(table, _CHAIN_KEYS, path)
        rotation = self.matrix(table, "rotation", path, np.eye(3).tolist())
        if not (np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-12) and np.linalg.det(rotation) > 0):
            self.fail(path + ("rotation",), rotation.tolist(), "must be a rotation matrix (orthonormal, det +1)")
        links_data = table.get("links")
        if not (isinstance(links_data, list) and links_data):
            self.fail(path + ("links",), links_data, "need at least one [[chains.links]] table")
        rows = [self.link(l, path + ("links", j)) for j, l in enumerate(links_data)]
        joints, links, infos = zip(*[(r[0], r[1], r[2]) for r in rows])
        chain = SerialChain(tuple(joints), tuple(links), rotor_inertia=tuple(r[3] for r in rows),
                            gear_ratio=tuple(r[4] for r in rows))
        name = table.get("name", f"chain{path[1] + 1}")
        return ChainSpec(str(name), chain, tuple(infos), self.vector(table, "base", path, (0.0, 0.0, 0.0)),
                         tuple(map(tuple, rotation)), self.vector(table, "attach", path, (0.0, 0.0, 0.0)))

    def link(self, table, path):
        if not isinstance(table, dict):
            self.fail(path, table, "must be a table")
        self.known(table, _LINK_KEYS, path)
        kind = table.get("joint", REVOLUTE)
        if kind not in (REVOLUTE, PRISMATIC):
            self.fail(path + ("joint",), kind, "must be 'R' (revolute) or 'P' (prismatic)")
        joint = DHJoint(kind, a=self.number(table, "a", path, 0.0), alpha=self.number(table, "alpha", path, 0.0),
                        d=self.number(table, "d", path, 0.0), theta=self.number(table, "theta", path, 0.0))
        inertia = self.inertia(table, path)
        link = RigidLink(self.number(table, "mass", path, 0.0, minimum=0.0),
                         self.vector(table, "com", path, (0.0, 0.0, 0.0)), inertia)
        for k, point in enumerate(table.get("point_masses", [])):
            ppath = path + ("point_masses", k)
            if not isinstance(point, dict):
                self.fail(ppath, point, "must be a table")
            self.known(point, _POINT_KEYS, ppath)
            link = with_point_mass(link, self.number(point, "mass", ppath, minimum=0.0), self.vector(point, "at", ppath))
        if "name" not in table:     # the joint's outputs are named by it: no name can stand in
            self.fail(path + ("name",), None, "missing (required): the joint's output name")
        name = table["name"]
        if not (isinstance(name, str) and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name)):
            self.fail(path + ("name",), name, "must be an identifier (letters, digits, _)")
        actuated = table.get("actuated", False)
        if not isinstance(actuated, bool):
            self.fail(path + ("actuated",), actuated, "must be true or false")
        default_input = "tau" + name[1:] if name.startswith("q") else f"tau_{name}"
        tau = table.get("input", default_input if actuated else "")
        if actuated and not (isinstance(tau, str) and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", tau)):
            self.fail(path + ("input",), tau, "must be an identifier (letters, digits, _)")
        info = JointInfo(name, actuated, self.number(table, "mode", path, 0.0), tau if actuated else "")
        rotor = self.number(table, "rotor_inertia", path, 0.0, minimum=0.0)
        gear = self.number(table, "gear_ratio", path, 1.0)
        return joint, link, info, rotor, gear

    def inertia(self, table, path):
        value = table.get("inertia", [0.0, 0.0, 0.0])
        if isinstance(value, list) and len(value) == 3 and all(isinstance(v, list) for v in value):
            inertia = self.matrix(table, "inertia", path, None)
        else:
            inertia = np.diag(self.vector(table, "inertia", path, default=(0.0, 0.0, 0.0)))
        eig = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
        if not np.allclose(inertia, inertia.T, atol=1e-15) or eig.min() < -1e-15:
            self.fail(path + ("inertia",), inertia.tolist(), "must be symmetric positive semi-definite [kg m2]")
        return inertia


def _dotted(path: tuple) -> str:
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else part)
    return out


def _find_line(lines, path: tuple) -> int | None:
    """The line defining ``path`` (or its deepest table found): follows ``[[a.b]]`` headers,
    counting each array of tables within its parent, and ``key =`` lines within a table."""
    target = tuple(path)
    counters: dict = {}
    current: tuple = ()
    best = None
    for number, raw in enumerate(lines, start=1):
        line = raw.split("#", 1)[0].strip()
        header = re.fullmatch(r"\[\[\s*([\w.]+)\s*\]\]|\[\s*([\w.]+)\s*\]", line)
        if header:
            names = (header.group(1) or header.group(2)).split(".")
            resolved = []
            for depth, name in enumerate(names):
                key = tuple(resolved) + (name,)
                if depth == len(names) - 1 and header.group(1):    # one more table of this array
                    counters[key] = counters.get(key, -1) + 1
                resolved.append(name)
                if key in counters:
                    resolved.append(counters[key])
            current = tuple(resolved)
            if target[:len(current)] == current:
                best = number
            continue
        m = re.match(r"([\w]+)\s*=", line)
        if m and current + (m.group(1),) == target[:len(current) + 1]:
            best = number
    return best

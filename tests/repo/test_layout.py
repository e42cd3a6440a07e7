"""The product's imports point down a fixed order of layers and form no cycle (issue 29, item 1).

Every ``import`` and ``from ... import`` of the product packages is read with :mod:`ast`, at module
level and inside functions alike (a lazy import is an import).  Each module belongs to the
group of its longest listed prefix (:data:`LAYERS`); an import from a lower layer to a higher
one fails, and so does a cycle, between modules or between groups.

Catches: a lazy import that closes a cycle (``scenes -> twin -> scenes``), a lower layer
reaching up (the master importing a study, a slave importing the co-simulation), a new
module in a folder no layer names, an old module name (``fmus.moved``) used inside the
product instead of its new one, or an alias that points nowhere.
"""
from __future__ import annotations

import ast
import importlib.util
import subprocess
import sys

import pytest
from tests.support.paths import ROOT

PACKAGES = ("kernels", "motor", "plant", "controller", "fmus", "scenarios", "parcosim")

#: Bottom first: a module may import from its own layer (if that closes no cycle) and below.
#: A group is a module prefix; a module belongs to the longest prefix listed.
LAYERS = (
    ("kernels",),                                   # each model's step once, in C, and its binding
    ("motor",),                                     # DC motor, current controller, observer, friction
    ("plant",),                                     # mechanisms (the actuated 5R uses the motor)
    ("controller",),                                # derivators, trajectories, position and balance laws
    ("fmus", "fmus.moved", "fmus.slave"),           # the slave base and what every slave shares
    ("fmus.export",),                               # FMU files: build, bundle, wrapper, ModelStructure
    ("fmus.cosim",),                                # system, master, stepper, back ends, foreign FMUs, compiled loop
    ("fmus.systemfmu",),                            # a system inside one FMU
    ("fmus.slaves",),                               # the pythonfmu slave scripts (ClosedLoop uses systemfmu)
    ("fmus.native",),                               # native FMUs, generated from the slaves' declarations and the kernels
    ("fmus.ssp",),                                  # SSP packages: export, read, run in other tools
    ("fmus.hostile",),                              # hostile use of the built FMUs
    ("scenarios", "scenarios.scenes"),              # scenes as data
    ("scenarios.run", "scenarios.reference"),       # running one scene; the monolithic reference
    ("scenarios.batch", "scenarios.packaging"),     # many runs on dask; a scene as an SSP package
    ("scenarios.studies",),                         # studies (write under out/)
    ("scenarios.examples",),                        # examples a user copies
    ("parcosim",),                                  # the command line
)
LAYER = {group: number for number, groups in enumerate(LAYERS) for group in groups}


def _modules() -> dict:
    """Dotted name -> file of every product module."""
    found = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join(parts)] = path
    return found


MODULES = _modules()


def _owner(name: str) -> str | None:
    """The product module an imported name lives in (``fmus.cosim.master.simulate`` ->
    ``fmus.cosim.master``), None outside the product."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name or None


def imports_of(module: str) -> dict:
    """Product module -> first line importing it, for every import in ``module`` (any depth)."""
    path = MODULES[module]
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = {}
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(parts + ([node.module] if node.module else []))
            names = [f"{base}.{a.name}" for a in node.names] or [base]
        else:
            continue
        for name in names:
            target = _owner(name)
            if target and target != module:
                found.setdefault(target, node.lineno)
    return found


GRAPH = {module: imports_of(module) for module in MODULES}


def group_of(module: str) -> str:
    """The longest prefix of :data:`LAYERS` that ``module`` is in."""
    matches = [g for g in LAYER if module == g or module.startswith(g + ".")]
    if not matches:
        raise KeyError(f"{module} ({MODULES[module].relative_to(ROOT)}) is in no layer of tests/repo/test_layout.py")
    return max(matches, key=len)


def _cycles(graph: dict) -> list:
    """The strongly connected components of more than one node (Tarjan, iterative)."""
    index, low, stack, on_stack, found, counter = {}, {}, [], set(), [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(graph[root]))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(graph[child])))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_the_reader_finds_lazy_and_relative_imports(tmp_path):
    """The parsing below sees what it must (an empty graph would pass everything)."""
    assert len(MODULES) > 130 and sum(map(len, GRAPH.values())) > 400
    # fmus/native keeps relative imports; imports inside functions count
    assert "fmus.native.models" in GRAPH["fmus.native.build"]
    assert "fmus.cosim.foreign" in GRAPH["fmus.cosim.master"]        # imported inside _instantiate


def test_every_module_is_in_a_layer():
    """Catches a new folder or module no layer names, which the direction check would skip."""
    unplaced = []
    for module in MODULES:
        try:
            group_of(module)
        except KeyError as exc:
            unplaced.append(str(exc))
    assert not unplaced, unplaced


def test_no_import_cycle_between_modules():
    assert not _cycles(GRAPH), _cycles(GRAPH)


def test_no_import_cycle_between_folders():
    groups = {}
    for module, targets in GRAPH.items():
        edges = groups.setdefault(group_of(module), set())
        edges.update(group_of(t) for t in targets if group_of(t) != group_of(module))
    assert not _cycles(groups), _cycles(groups)


def test_imports_point_down():
    """Catches a module importing from a layer above its own (docs/layout.md's table)."""
    upward = [f"{MODULES[m].relative_to(ROOT)}:{line}: {m} ({group_of(m)}) imports {t} ({group_of(t)})"
              for m, targets in GRAPH.items() for t, line in targets.items()
              if LAYER[group_of(t)] > LAYER[group_of(m)]]
    assert not upward, upward


def test_the_cycle_detector_finds_a_lazy_cycle():
    """The detector itself: a two-module cycle through a function's import is reported."""
    assert _cycles({"a": {"b": 1}, "b": {"a": 9}, "c": {"a": 2}}) == [["a", "b"]]
    assert _cycles({"a": {"b": 1}, "b": {}}) == []


def _moved_tables() -> dict:
    import fmus
    import scenarios

    return {**fmus.MOVED, **scenarios.MOVED}


def test_old_module_names_lead_to_existing_modules():
    """Catches an alias table entry pointing to a module that moved again or was removed, or an old name
    that became a module again."""
    moved = _moved_tables()
    assert len(moved) > 50
    assert not [f"{old} -> {new}" for old, new in moved.items() if new not in MODULES]
    assert not [old for old in moved if old in MODULES], "an old name is a module again"


def test_the_product_imports_no_old_name():
    """Catches product code importing a module by its pre-layout name (it works through the alias, so
    nothing else fails)."""
    moved = _moved_tables()
    old = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module, *(f"{node.module}.{a.name}" for a in node.names)] \
                if isinstance(node, ast.ImportFrom) and node.module and not node.level else []
            old += [f"{module}:{node.lineno}: {n}" for n in names if n in moved]
    assert not old, old


def test_an_old_name_is_the_new_module_and_runs_with_python_m():
    """Catches an alias that loads a second copy of the module (its globals then differ) or a moved command
    that python -m no longer runs."""
    import fmus.cosim.master
    import scenarios.studies.tools

    importlib.import_module("fmus.master")
    assert sys.modules["fmus.master"] is fmus.cosim.master
    assert sys.modules["fmus.master"].__spec__.name == "fmus.cosim.master"   # its own spec kept
    assert importlib.import_module("scenarios.tools") is scenarios.studies.tools
    run = subprocess.run([sys.executable, "-m", "scenarios.tools", "--help"], cwd=ROOT, capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0 and "--tools" in run.stdout, run.stderr


@pytest.mark.parametrize("old, attribute", [("scenarios.scenes", "get_scene"), ("scenarios.scenes", "drives_in_plant"),
                                            ("scenarios.scenes", "with_fmu_files"), ("scenarios.run", "run_scene"),
                                            ("fmus.ssp", "export_ssp")])
def test_a_package_that_was_a_module_keeps_its_public_names(old, attribute):
    """Catches a module turned into a package that no longer re-exports the names user code imports from
    it."""
    assert callable(getattr(importlib.import_module(old), attribute))
    assert importlib.util.find_spec(old).submodule_search_locations is not None


def _output_defaults():
    """(where, default) of every ``--out`` option and every ``out_dir``/``out`` parameter given a
    string default in ``scenarios/`` (the studies, batch work and examples)."""
    for module, path in MODULES.items():
        if not module.startswith("scenarios."):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            where = f"{path.relative_to(ROOT)}:{getattr(node, 'lineno', 0)}"
            if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "add_argument" \
                    and node.args and isinstance(node.args[0], ast.Constant) and node.args[0].value == "--out":
                yield from ((where, k.value.value) for k in node.keywords
                            if k.arg == "default" and isinstance(k.value, ast.Constant) and k.value.value is not None)
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                arguments = node.args.args[len(node.args.args) - len(node.args.defaults):]
                yield from ((where, d.value) for a, d in zip(arguments, node.args.defaults)
                            if a.arg in ("out", "out_dir") and isinstance(d, ast.Constant) and isinstance(d.value, str))


def test_studies_write_under_out_unless_told_to_write_the_docs():
    """A study run plainly writes under out/; the repository's docs/ change only through an
    explicit ``--docs`` (or an explicit path)."""
    found = list(_output_defaults())
    assert len(found) >= 5
    assert not [f"{where}: default {value!r}" for where, value in found if value != "out" and not value.startswith("out/")]


def test_fmus_and_scenarios_import_absolutely():
    """A relative import in a moved file points at the old neighbourhood (``from .guarded import``
    in fmus/cosim/ looks for fmus.cosim.guarded); ``fmus/`` and ``scenarios/`` name modules in full
    (fmus/native/, which did not move, keeps its own)."""
    relative = [f"{MODULES[m].relative_to(ROOT)}:{node.lineno}" for m in MODULES
                if m.startswith(("fmus.", "scenarios.")) and not m.startswith("fmus.native")
                for node in ast.walk(ast.parse(MODULES[m].read_text(encoding="utf-8")))
                if isinstance(node, ast.ImportFrom) and node.level]
    assert not relative, relative

"""Mutation testing of parcosim, Python and C in one campaign, out of sample (issue 31).

The pool is every product module: the Python of ``plant/``, ``motor/``, ``controller/``,
``fmus/`` (slaves, export, SSP, state, refusals...), ``scenarios/``, ``parcosim/`` and
``kernels/`` (mutants made here, on the syntax tree), and ``kernels/src/*.c``
(:mod:`benchmarks.mutation_c`'s mutants).  A seeded sample draws a file with a probability
proportional to its lines, then one of the operators that has mutants in it, then one of
that operator's mutants (so no operator crowds out the others), without repetition.  Each
mutant runs in a copy of the source tree (one per worker; the worktree is never written)
against the tests that import its module, directly or through one other module (computed
from the import statements and the module names in strings of the tests and the product;
the nearest 6, direct importers first, then the light and the smaller files), with
``pytest -x`` and a CPU-time limit (the wall clock's is 8 times longer: on shared cores a
run mostly waits for one).  A C mutant is built into its own library (mutation_c) and runs
the kernel tests and the oracle tests.

    python -m benchmarks.mutation_py --seed 3101 --sample 300 --workers 2   # run (resumes)
    python -m benchmarks.mutation_py --report                               # the table again
    python -m benchmarks.mutation_py --pool                                 # every mutant

Outcomes: ``killed`` (a test failed or errored), ``survived`` (every selected test passed,
or no test imports the module), ``not viable`` (the mutant does not compile), ``timeout``
(a time limit ended the run: not decided, listed apart).  A killed mutant's first failing
test is recorded; ``--confirm`` re-runs those tests on the unmutated tree, so a test that
fails anyway cannot count as a kill.

Python operators (``ast``; never docstrings, annotations or f-string parts):

``arith``         ``+``/``-``, ``*``/``/``, ``//`` -> ``/``, ``**`` -> ``*``
``compare``       ``<``/``<=``, ``>``/``>=``, ``==``/``!=``, ``is``/``is not``, ``in``/``not in``
``boolean``       ``and``/``or``; ``not x`` -> ``x``; ``-x`` -> ``x``
``constant``      a number times 2 (``0`` -> ``1``)
``drop_term``     ``a + b`` -> ``a`` or ``b``, ``a - b`` -> ``a``, ``a * b`` -> ``a`` or ``b``, ``a / b`` -> ``a``
``drop_arg``      one argument of a call left out (positional or keyword)
``swap_args``     two adjacent positional arguments of one call swapped
``swap_index``    ``a[i][j]`` -> ``a[j][i]``, ``a[i, j]`` -> ``a[j, i]``
``replace_var``   a local name read in a function -> another local of the same kind defined
                  before it (same annotation, or assigned the same kind of value)
"""
from __future__ import annotations

import argparse
import ast
import json
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

from benchmarks import mutation_c, mutation_map

ROOT = Path(__file__).resolve().parent.parent

PACKAGES = ("plant", "motor", "controller", "fmus", "scenarios", "parcosim", "kernels")
#: Test files no mutant runs: the mutation tools' own, and the sanitizer build of pristine C.
NOT_RUN = mutation_map.NOT_RUN
#: The tests a C mutant runs (besides mutation_c's extra ones): the kernels' and the oracles'.
C_TESTS = ("tests/kernels/test_kernels_*.py", "tests/**/test_oracles_*.py")
#: How many imports away a test may reach a module and still run for its mutants, and how
#: many test files (the nearest, then the smallest) a mutant runs at most.
NEAR, MOST_TESTS = 2, 6
#: A file of long runs (``pytest -m slow``: sanitizer builds, hostile campaigns, dask sweeps,
#: other tools): a Python mutant does not run it (one such file takes minutes to tens of them).
SLOW = re.compile(r"^pytestmark = .*pytest\.mark\.slow", re.M)
#: A test run's wall-clock limit, in multiples of its CPU-time limit (``--timeout``).
WALL_FACTOR = 8
#: Words of a test file that builds FMUs or starts processes: it runs after the others of its
#: distance (``-x`` stops at the first failure, so a cheap test that fails saves the rest).
HEAVY = ("built_fmus", "subprocess", "build_all", "ensure_built")


@dataclass(frozen=True)
class PyMutant:
    """In ``file`` (relative to the root), the text from (line, column) to (end_line,
    end_column) (1-based lines, 0-based character columns) becomes ``after``."""

    file: str
    line: int
    column: int
    end_line: int
    end_column: int
    operator: str
    before: str
    after: str

    def apply(self, text: str) -> str:
        """``text`` (the whole file) with this change."""
        lines = text.split("\n")
        first, last = lines[self.line - 1], lines[self.end_line - 1]
        span = "\n".join([first[self.column:]] + lines[self.line:self.end_line - 1]) if self.end_line > self.line \
            else ""
        found = (span + "\n" + last[:self.end_column]) if self.end_line > self.line else first[self.column:self.end_column]
        if found != self.before:
            raise ValueError(f"{self.file}:{self.line}: {self.before[:40]!r} is not where it was")
        changed = first[:self.column] + self.after + last[self.end_column:]
        return "\n".join(lines[:self.line - 1] + [changed] + lines[self.end_line:])


# --- the Python operators ------------------------------------------------------------------
_ARITH = {ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult, ast.FloorDiv: ast.Div,
          ast.Pow: ast.Mult}
_COMPARE = {ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt, ast.Eq: ast.NotEq,
            ast.NotEq: ast.Eq, ast.Is: ast.IsNot, ast.IsNot: ast.Is, ast.In: ast.NotIn, ast.NotIn: ast.In}


def _copy(node, **changes):
    new = type(node)(**{f: getattr(node, f) for f in node._fields})
    for name, value in changes.items():
        setattr(new, name, value)
    return new


def arith(node):
    if isinstance(node, ast.BinOp) and type(node.op) in _ARITH:
        yield _copy(node, op=_ARITH[type(node.op)]())
    elif isinstance(node, ast.AugAssign) and type(node.op) in _ARITH:
        yield _copy(node, op=_ARITH[type(node.op)]())


def compare(node):
    if isinstance(node, ast.Compare):
        for k, op in enumerate(node.ops):
            if type(op) in _COMPARE:
                ops = list(node.ops)
                ops[k] = _COMPARE[type(op)]()
                yield _copy(node, ops=ops)


def boolean(node):
    if isinstance(node, ast.BoolOp):
        yield _copy(node, op=ast.Or() if isinstance(node.op, ast.And) else ast.And())
    elif isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.Not, ast.USub)):
        yield node.operand


def constant(node):
    if isinstance(node, ast.Constant) and type(node.value) in (int, float):
        yield ast.Constant(value=node.value * 2 if node.value else type(node.value)(1))


def drop_term(node):
    if isinstance(node, ast.BinOp):
        if isinstance(node.op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
            yield node.left
        if isinstance(node.op, (ast.Add, ast.Mult)):
            yield node.right


def drop_arg(node):
    if isinstance(node, ast.Call):
        for k in range(len(node.args)):
            yield _copy(node, args=node.args[:k] + node.args[k + 1:])
        for k in range(len(node.keywords)):
            yield _copy(node, keywords=node.keywords[:k] + node.keywords[k + 1:])


def swap_args(node):
    if isinstance(node, ast.Call):
        for k in range(len(node.args) - 1):
            a, b = node.args[k], node.args[k + 1]
            if not isinstance(a, ast.Starred) and not isinstance(b, ast.Starred) and ast.dump(a) != ast.dump(b):
                args = list(node.args)
                args[k], args[k + 1] = b, a
                yield _copy(node, args=args)


def swap_index(node):
    if not isinstance(node, ast.Subscript):
        return
    if isinstance(node.value, ast.Subscript) and ast.dump(node.slice) != ast.dump(node.value.slice):
        inner = _copy(node.value, slice=node.slice)
        yield _copy(node, value=inner, slice=node.value.slice)
    if isinstance(node.slice, ast.Tuple):
        items = node.slice.elts
        for k in range(len(items) - 1):
            if ast.dump(items[k]) != ast.dump(items[k + 1]):
                swapped = list(items)
                swapped[k], swapped[k + 1] = items[k + 1], items[k]
                yield _copy(node, slice=_copy(node.slice, elts=swapped))


PY_OPERATORS = {"arith": arith, "compare": compare, "boolean": boolean, "constant": constant, "drop_term": drop_term,
                "drop_arg": drop_arg, "swap_args": swap_args, "swap_index": swap_index}


def _kind(value, kinds: dict):
    """The kind of a value assigned to a local (None: not a candidate for replace_var)."""
    if isinstance(value, ast.Constant) and not isinstance(value.value, (str, bytes)) and value.value is not None:
        return "number" if type(value.value) in (int, float) else type(value.value).__name__
    if isinstance(value, (ast.BinOp, ast.UnaryOp)):
        return "number"
    if isinstance(value, ast.Call):
        return "call:" + ast.unparse(value.func)
    if isinstance(value, ast.Name):
        return kinds.get(value.id)
    return None


def _locals(function) -> dict:
    """name -> (kind, line it is first defined at) of a function's parameters and the names
    it assigns (a simple name, one target)."""
    found = {}
    a = function.args
    for arg in a.posonlyargs + a.args + a.kwonlyargs:
        if arg.arg not in ("self", "cls"):
            kind = "annotated:" + ast.unparse(arg.annotation) if arg.annotation is not None else "parameter"
            found[arg.arg] = (kind, function.lineno)
    kinds = {name: kind for name, (kind, _) in found.items()}
    for node in ast.walk(function):
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node is not function:
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if len(targets) == 1 and isinstance(targets[0], ast.Name) and node.value is not None:
                name = targets[0].id
                kind = ("annotated:" + ast.unparse(node.annotation) if isinstance(node, ast.AnnAssign)
                        else _kind(node.value, kinds))
                if name not in found and kind is not None:
                    found[name] = (kind, node.lineno)
                    kinds[name] = kind
    return found


def replace_var(node, scope):
    if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Load) and scope and node.id in scope:
        kind = scope[node.id][0]
        for other, (other_kind, line) in scope.items():
            if other != node.id and other_kind == kind and line < node.lineno:
                yield ast.Name(id=other, ctx=ast.Load())


def _skipped(tree) -> set:
    """ids of nodes never mutated: docstrings, annotations, f-strings and what they hold."""
    skip = set()

    def mark(node):
        if node is not None:
            skip.update(id(n) for n in ast.walk(node))

    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                mark(first)
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            mark(node.returns)
            for arg in node.args.posonlyargs + node.args.args + node.args.kwonlyargs:
                mark(arg.annotation)
        elif isinstance(node, ast.AnnAssign):
            mark(node.annotation)
        elif isinstance(node, ast.JoinedStr):
            mark(node)
    return skip


def _text(new) -> str:
    if isinstance(new, ast.AugAssign):
        return ast.unparse(new)
    return "(" + ast.unparse(new) + ")"


def mutants_of_python(name: str, text: str) -> list:
    """Every mutant of one Python file (``name`` relative to the root)."""
    tree = ast.parse(text)
    skip = _skipped(tree)
    lines = text.split("\n")
    scopes = {}
    for function in ast.walk(tree):
        if isinstance(function, (ast.FunctionDef, ast.AsyncFunctionDef)):
            scope = _locals(function)
            for node in ast.walk(function):
                scopes[id(node)] = scope      # the innermost function wins (walked later)
    raw = [line.encode() for line in lines]
    generators = dict(PY_OPERATORS, replace_var=lambda n: replace_var(n, scopes.get(id(n))))
    found = []
    for node in ast.walk(tree):
        if id(node) in skip or not hasattr(node, "end_col_offset"):
            continue
        if isinstance(node, ast.AugAssign) and node.lineno != node.end_lineno:
            continue
        mutations = [(operator, new) for operator, generate in generators.items() for new in generate(node)]
        if not mutations:
            continue
        line, end = node.lineno, node.end_lineno
        column = len(raw[line - 1][:node.col_offset].decode(errors="replace"))
        end_column = len(raw[end - 1][:node.end_col_offset].decode(errors="replace"))
        if line == end:
            before = lines[line - 1][column:end_column]
        else:
            before = "\n".join([lines[line - 1][column:]] + lines[line:end - 1] + [lines[end - 1][:end_column]])
        for operator, new in mutations:
            after = _text(new)
            if after.strip("()") != before:
                found.append(PyMutant(name, line, column, end, end_column, operator, before, after))
    return found


# --- the pool and the draw -----------------------------------------------------------------
def python_files() -> list:
    """The product's Python files, relative to the root."""
    return sorted(str(p.relative_to(ROOT)) for package in PACKAGES for p in (ROOT / package).rglob("*.py"))


def c_files() -> list:
    return sorted(f"kernels/src/{p.name}" for p in mutation_c.kbuild.SOURCES.glob("*.c"))


def pool_by_file() -> dict:
    """file -> its mutants (Python: PyMutant; C: mutation_c.Mutant)."""
    pool = {name: mutants_of_python(name, (ROOT / name).read_text()) for name in python_files()}
    for name in c_files():
        pool[name] = mutation_c.mutants_of(Path(name).name, (ROOT / name).read_text())
    return pool


def line_count(name: str) -> int:
    return len((ROOT / name).read_text().split("\n"))


def draw(pool: dict, seed: int, sample: int) -> list:
    """``sample`` distinct mutants: a file by its lines, an operator of it, a mutant of that."""
    rng = random.Random(seed)
    files = [name for name in sorted(pool) if pool[name]]
    weights = [line_count(name) for name in files]
    chosen, seen = [], set()
    while len(chosen) < min(sample, sum(len(pool[f]) for f in files)):
        name = rng.choices(files, weights)[0]
        by_operator = {}
        for m in pool[name]:
            by_operator.setdefault(m.operator, []).append(m)
        operator = rng.choice(sorted(by_operator))
        mutant = rng.choice(by_operator[operator])
        key = (name, *asdict(mutant).values())
        if key not in seen:
            seen.add(key)
            chosen.append((name, mutant))
    return chosen


# --- which tests import a module -----------------------------------------------------------
def module_name(path: str) -> str:
    parts = Path(path).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, own: str) -> set:
    """The modules a file imports (anywhere in it), resolved against the tree: ``from a import b``
    names a.b when that is a module, and every parent package is imported too."""
    tree = ast.parse(path.read_text())
    package = own if path.name == "__init__.py" else own.rpartition(".")[0]
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    names |= _named_in_strings(tree, package)
    found = set()
    for name in names:
        parts = name.split(".")
        for k in range(1, len(parts) + 1):
            candidate = ".".join(parts[:k])
            if (ROOT / Path(*parts[:k])).with_suffix(".py").exists() or (ROOT / Path(*parts[:k]) / "__init__.py").exists():
                found.add(candidate)
    return found


def _named_in_strings(tree, package: str) -> set:
    """Modules a file loads by name (``importlib``, a package's lazy ``__getattr__``): a string
    that is a dotted module name, a prefix such as ``"fmus.slaves."`` (every module under it;
    a leading dot is relative to the file's package), or, in a package, a submodule's name."""
    found = set()
    modules = [module_name(f) for f in python_files()]
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Constant) and isinstance(node.value, str)) or len(node.value) > 80:
            continue
        text = node.value
        if text.startswith("."):
            text = package + text
        if text.endswith("."):
            found.update(m for m in modules if m.startswith(text))
        elif text in modules or f"{package}.{text}" in modules:
            found.add(text if text in modules else f"{package}.{text}")
    return found


def test_map(root: Path = ROOT) -> dict:
    """Product module -> the test files that import it, or import a module that imports it
    (:data:`NEAR` imports away at most: a package's ``__init__`` names all its modules, so the
    full closure is nearly every test), the nearer first, then those that build no FMU and
    start no process, then the smaller, at most :data:`MOST_TESTS` of them; never a
    :data:`SLOW` file.  ``root``: the tree whose tests are read (a campaign's copy of its
    commit)."""
    graph = {}
    for path in [root / f for f in python_files()] + sorted((root / "tests").rglob("*.py")):
        own = module_name(str(path.relative_to(root)))
        graph[own] = _imports(path, own)
    tests = [p for p in sorted((root / "tests").rglob("test_*.py"))
             if not str(p.relative_to(root)).startswith(NOT_RUN) and not SLOW.search(p.read_text())]
    mapping = {}
    for test in tests:
        own = module_name(str(test.relative_to(root)))
        distance, frontier = {}, set(graph[own])
        for step in range(1, NEAR + 1):
            frontier = {m for m in frontier if m not in distance}
            distance.update((m, step) for m in frontier)
            frontier = {n for m in frontier for n in graph.get(m, ())}
        text = test.read_text()
        heavy = any(word in text for word in HEAVY)
        for m, d in distance.items():
            mapping.setdefault(m, []).append((d, heavy, test.stat().st_size, str(test.relative_to(root))))
    return {m: [entry[-1] for entry in sorted(entries)][:MOST_TESTS] for m, entries in mapping.items()}


# --- running -------------------------------------------------------------------------------
def results_path(seed: int) -> Path:
    """Where a seed's campaign keeps its outcomes: one JSON line a mutant, appended as each is
    decided (a restart resumes), in the repository."""
    return ROOT / "benchmarks" / "results" / f"mutation_{seed}.jsonl"


def make_copy(where: Path, commit: str = "HEAD") -> Path:
    """The committed tree (``git archive <commit>``) at ``where``, with the built kernels library."""
    shutil.rmtree(where, ignore_errors=True)
    where.mkdir(parents=True)
    archive = subprocess.run(["git", "archive", commit], cwd=ROOT, check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(where)], input=archive, check=True)
    shutil.copy2(mutation_c.kbuild.build(), where / "kernels" / mutation_c.kbuild.LIBRARY.name)
    return where


def _cpu_limit(seconds: float):
    """The child's CPU-time limit (SIGXCPU past it): on shared cores a wall-clock limit ends
    runs that were only waiting for a core."""
    def limit():
        resource.setrlimit(resource.RLIMIT_CPU, (int(seconds), int(seconds) + 5))
    return limit


def _pytest(copy: Path, tests: list, timeout: float, env: dict) -> dict:
    """``pytest -x`` of ``tests`` (files or node ids, in that order) in ``copy``, at most
    ``timeout`` CPU seconds (and :data:`WALL_FACTOR` times as many on the wall clock)."""
    cache = tempfile.mkdtemp(prefix="parcosim_mutcache_")
    env = dict(env, PYTHONDONTWRITEBYTECODE="1", PARCOSIM_CACHE=cache,
               PYTHONPATH=os.pathsep.join([str(copy), *mutation_map._other_paths()]))
    listed = Path(cache) / "tests.txt"
    listed.write_text("\n".join(tests) + "\n")
    start = time.monotonic()
    try:
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "-rf",
                               f"@{listed}"], cwd=copy, env=env, timeout=WALL_FACTOR * timeout,
                              capture_output=True, text=True, preexec_fn=_cpu_limit(timeout))
    except subprocess.TimeoutExpired:
        return {"outcome": "timeout", "seconds": WALL_FACTOR * timeout, "cpu_limit": timeout}
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    seconds = round(time.monotonic() - start, 1)
    if done.returncode == -signal.SIGXCPU:
        return {"outcome": "timeout", "seconds": seconds, "cpu_limit": timeout}
    failed = re.findall(r"^(?:FAILED|ERROR) (\S+)", done.stdout, re.M)
    outcome = {0: "survived", 1: "killed", 2: "killed", 5: "survived"}.get(done.returncode, "error")
    return {"outcome": outcome, "seconds": seconds, "returncode": done.returncode, "failed": failed[:1],
            "cpu_limit": timeout}


def _limit(cost: float, base: float, factor: float) -> float:
    """A run's CPU-time limit from its tests' measured seconds."""
    return round(base + factor * cost)


def run_python(copy: Path, mutant: PyMutant, chosen: dict, base: float, factor: float) -> dict:
    """Run ``mutant`` against ``chosen`` (:func:`select`'s answer)."""
    path = copy / mutant.file
    original = path.read_text()
    mutated = mutant.apply(original)
    try:
        compile(mutated, str(path), "exec")
    except SyntaxError:
        return {"outcome": "not viable", "seconds": 0.0}
    if not chosen["tests"]:
        return {"outcome": "survived", "seconds": 0.0, "note": chosen["note"]}
    try:
        path.write_text(mutated)
        return _pytest(copy, chosen["tests"], _limit(chosen["cost"], base, factor), dict(os.environ))
    finally:
        path.write_text(original)


def run_c(copy: Path, mutant, chosen: dict, base: float, factor: float) -> dict:
    work = Path(tempfile.mkdtemp(prefix="parcosim_cmut_"))
    try:
        sources = work / "src"
        shutil.copytree(copy / "kernels" / "src", sources)
        target = sources / mutant.file
        target.write_text(mutant.apply(target.read_text()))
        try:
            library = mutation_c.build_from(sources, work / "libparcosim_kernels.so")
        except subprocess.CalledProcessError:
            return {"outcome": "not viable", "seconds": 0.0}
        return _pytest(copy, chosen["tests"], _limit(chosen["cost"], base, factor),
                       dict(os.environ, PARCOSIM_KERNELS_LIB=str(library)))
    finally:
        shutil.rmtree(work, ignore_errors=True)


def select(copy: Path, name: str, mutant, near: list, budget: float, lock_of=None, commit: str = "HEAD") -> dict:
    """The tests a mutant runs.  Python: among the test files of ``near`` (the nearest
    importers of its module, :func:`test_map`), those tests that execute a line it changes
    (:mod:`benchmarks.mutation_map`, each file's map built in ``copy`` the first time); all of
    ``near`` when only import-time or subprocess runs execute the lines; none when nothing
    does.  C (coverage does not see C lines): every test of the kernels' and the oracles'
    files (and mutation_c's extra ones), the cheaper first."""
    if name.endswith(".c"):
        files = sorted({str(p.relative_to(copy)) for pattern in C_TESTS for p in copy.glob(pattern)})
        files += mutation_c.EXTRA_TESTS.get(mutant.file, [])
        linemap = mutation_map.for_files(copy, python_files(), files, lock_of, commit)
        failing = set(linemap["failed"])
        tests = sorted((t for t in linemap["all_tests"] if t not in failing),
                       key=lambda t: linemap["all_tests"][t]["seconds"])
        return {"tests": tests, "covering": len(tests), "cost": round(mutation_map.cost(linemap, tests), 2),
                "selection": "C tests"}
    linemap = mutation_map.for_files(copy, python_files(), near, lock_of, commit)
    chosen = mutation_map.select(linemap, name, mutant.line, mutant.end_line, near, budget)
    if chosen["tests"] is None:
        return {"tests": near, "covering": 0, "cost": round(mutation_map.cost(linemap, list(linemap["all_tests"])), 2),
                "selection": "near files whole (a line run at import or in a subprocess)"}
    if not chosen["tests"]:
        return dict(chosen, selection="none", note=f"none of the {len(near)} nearest test files executes the line")
    return dict(chosen, selection="coverage")


def _record(name, mutant) -> dict:
    return {**asdict(mutant), "file": name, "language": "c" if name.endswith(".c") else "python"}


def read_results(results: Path) -> tuple:
    """(header, {index: outcome record}) of a campaign's JSON-lines file (the last line of an
    index wins: ``--retry-timeouts`` appends)."""
    header, done = None, {}
    for line in results.read_text().splitlines():
        if line.strip():
            entry = json.loads(line)
            if "header" in entry:
                header = entry["header"]
            else:
                done[entry["index"]] = entry
    return header, done


def campaign(seed: int, sample: int, workers: int, results: Path | None = None, retry_timeouts: bool = False,
             base: float = 30.0, factor: float = 3.0, budget: float = 300.0) -> Path:
    """Draw ``sample`` mutants with ``seed`` and run them, each against the tests that execute
    its lines (``budget``: at most so many measured seconds of them), with ``pytest -x`` and a
    CPU-time limit of ``base + factor * (their measured seconds)``; each outcome is appended
    to ``results`` as it comes (a restart with the same seed and sample resumes)."""
    results = results or results_path(seed)
    pool = pool_by_file()
    chosen = draw(pool, seed, sample)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    done = {}
    if results.exists():
        header, done = read_results(results)
        if header["seed"] != seed or header["sample"] != len(chosen):
            raise ValueError(f"{results} holds seed {header['seed']}, sample {header['sample']}, "
                             f"not seed {seed}, sample {len(chosen)}")
        if header.get("drawn") and header["drawn"] != [name for name, _ in chosen]:
            raise ValueError(f"{results} was drawn from the product files of commit {header['commit'][:10]}; "
                             f"this tree's draw differs (a file moved or changed since): resume from a checkout "
                             f"of that commit (git worktree add --detach DIR {header['commit'][:10]}) with this "
                             f"tool's benchmarks/mutation_*.py copied into it")
    else:
        results.parent.mkdir(parents=True, exist_ok=True)
        header = {"seed": seed, "sample": len(chosen), "commit": commit, "map": mutation_map.key(),
                  "near_files": MOST_TESTS,
                  "base_seconds": base, "factor": factor, "budget_seconds": budget,
                  "pool": {name: len(ms) for name, ms in pool.items()},
                  "lines": {name: line_count(name) for name in pool}, "drawn": [name for name, _ in chosen]}
        results.write_text(json.dumps({"header": header}) + "\n")
    copies = [make_copy(Path(tempfile.gettempdir()) / f"parcosim_mutpy_{os.getpid()}_{w}", header["commit"])
              for w in range(workers)]
    near_of = test_map(copies[0])     # the tests of the draw's commit: tests written since are not run
    lock, shards = threading.Lock(), {}

    def lock_of(test_file):            # one worker builds a test file's map, the other waits for it
        with lock:
            return shards.setdefault(test_file, threading.Lock())

    free = list(copies)

    def one(k):
        name, mutant = chosen[k]
        with lock:
            copy = free.pop()
        try:
            tests = select(copy, name, mutant, near_of.get(module_name(name), []), budget, lock_of,
                           header["commit"])
            run = run_c if name.endswith(".c") else run_python
            result = run(copy, mutant, tests, base, factor)
        finally:
            with lock:
                free.append(copy)
        entry = {"index": k, **_record(name, mutant), **result, "selection": tests["selection"],
                 "covering": tests["covering"], "selected": len(tests["tests"] or []), "cost": tests["cost"]}
        with lock:
            with results.open("a") as out:
                out.write(json.dumps(entry) + "\n")
            done[k] = entry
            print(f"[{len(done)}/{len(chosen)}] {name}:{mutant.line} {mutant.operator} {mutant.before[:50]!r} -> "
                  f"{mutant.after[:50]!r}: {result['outcome']} ({result['seconds']} s, {entry['selected']} tests)",
                  flush=True)

    pending = [k for k in range(len(chosen)) if k not in done]
    if retry_timeouts:     # after the rest
        pending += [k for k, m in sorted(done.items()) if m["outcome"] == "timeout"]
    try:
        with ThreadPoolExecutor(workers) as pool_:
            list(pool_.map(one, pending))
    finally:
        for copy in copies:
            shutil.rmtree(copy, ignore_errors=True)
    return results


def confirm(results: Path, timeout: float) -> dict:
    """Run every killing test once more, all in one run, on the unmutated tree; a kill by a
    test that fails there too is appended again as ``baseline failure``."""
    header, done = read_results(results)
    killers = sorted({t for m in done.values() if m["outcome"] == "killed" for t in m.get("failed", [])})
    copy = make_copy(Path(tempfile.gettempdir()) / f"parcosim_mutpy_confirm_{os.getpid()}")
    try:
        ran = _pytest_all(copy, killers, timeout * max(1, len(killers)))
    finally:
        shutil.rmtree(copy, ignore_errors=True)
    failing = set(re.findall(r"^(?:FAILED|ERROR) (\S+)", ran.stdout, re.M))
    with results.open("a") as out:
        for m in done.values():
            if m["outcome"] == "killed" and m.get("failed") and m["failed"][0] in failing:
                out.write(json.dumps(dict(m, outcome="baseline failure")) + "\n")
    return {"tests": len(killers), "returncode": ran.returncode, "failing_on_the_unmutated_tree": sorted(failing)}


def _pytest_all(copy: Path, tests: list, timeout: float):
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.pathsep.join([str(copy), *mutation_map._other_paths()]))
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rf", *tests],
                          cwd=copy, env=env, timeout=WALL_FACTOR * timeout, capture_output=True, text=True)


def main(argv=None) -> int:
    from benchmarks.mutation_report import table

    parser = argparse.ArgumentParser(prog="python -m benchmarks.mutation_py", description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=3501)
    parser.add_argument("--sample", type=int, default=300)
    parser.add_argument("--base", type=float, default=30.0, help="CPU seconds a test run may take besides its tests'")
    parser.add_argument("--factor", type=float, default=3.0,
                        help="a run's CPU-time limit in multiples of its tests' measured seconds (plus --base)")
    parser.add_argument("--budget", type=float, default=300.0,
                        help="measured seconds of tests a mutant runs at most (the nearest and cheapest first)")
    parser.add_argument("--retry-timeouts", action="store_true", help="run the timed-out mutants again, last")
    parser.add_argument("--workers", type=int, default=1, help="mutants run at once (one tree copy each)")
    parser.add_argument("--results", type=Path, help="the JSON-lines file (default: benchmarks/results/mutation_<seed>.jsonl)")
    parser.add_argument("--report", action="store_true", help="reprint the table from --results")
    parser.add_argument("--confirm", action="store_true", help="re-run the killing tests on the unmutated tree")
    parser.add_argument("--pool", action="store_true", help="list every mutant of the pool")
    args = parser.parse_args(argv)
    results = args.results or results_path(args.seed)
    if args.pool:
        for name, mutants in pool_by_file().items():
            for m in mutants:
                print(f"{name}:{m.line}:{m.column} {m.operator} {m.before[:60]!r} -> {m.after[:60]!r}")
        return 0
    if args.confirm:
        print(confirm(results, 90.0))
    elif not args.report:
        campaign(args.seed, args.sample, args.workers, results, args.retry_timeouts, args.base, args.factor,
                 args.budget)
    print(table(*read_results(results)))
    return 0


if __name__ == "__main__":
    sys.exit(main())

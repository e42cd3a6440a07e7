"""Mutation testing of parcosim, Python and C in one campaign, out of sample (issue 31).

The pool is every product module: the Python of ``plant/``, ``motor/``, ``controller/``,
``fmus/`` (slaves, export, SSP, state, refusals...), ``scenarios/``, ``parcosim/`` and
``kernels/`` (mutants made here, on the syntax tree), and ``kernels/src/*.c``
(:mod:`benchmarks.mutation_c`'s mutants).  A seeded sample draws a file with a probability
proportional to its lines, then one of the operators that has mutants in it, then one of
that operator's mutants (so no operator crowds out the others), without repetition.  Each
mutant runs in a copy of the source tree (one per worker; the worktree is never written)
against the tests, anywhere in the suite, that execute a line it changes, in process or in a
process they start (:mod:`benchmarks.mutation_map`'s per-test coverage of every test file;
a line run at import: the tests that execute its module, then the test files that import it,
directly or through one other module, computed from the import statements and the module
names in strings of the tests and the product), the cheaper first within a budget, with
``pytest -x`` and a CPU-time limit (:mod:`benchmarks.mutation_run`).  A C mutant is built
into its own library (mutation_c) and runs, the same way, the tests that execute its line in
process or in a process they start (:mod:`benchmarks.mutation_cmap`'s gcov map).

    python -m benchmarks.mutation_py --seed 3101 --sample 300 --workers 2   # run (resumes)
    python -m benchmarks.mutation_py --report                               # the table again
    python -m benchmarks.mutation_py --pool                                 # every mutant
    python -m benchmarks.mutation_py --seed 3601 --rerun-survivors OLD.jsonl --results NEW.jsonl \
        [--language c] [--outcomes error] [--c-test-files 'tests/kernels/*' ...]

Outcomes: ``killed`` (a test failed or errored, or the run failed loudly: the test files no
longer collect, a crash, pytest's internal error, while the same selection passes on the
unmutated tree; ``killed_by`` says which), ``survived`` (every selected test passed, or no
test executes the line), ``not viable`` (the mutant does not compile), ``timeout`` (a time
limit ended the run: not decided, listed apart), ``baseline failure`` (a loud failure the
unmutated tree fails too: not decided).  A killed mutant's first failing
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
import random
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

from benchmarks import mutation_c, mutation_map

ROOT = Path(__file__).resolve().parent.parent

PACKAGES = ("plant", "motor", "controller", "fmus", "scenarios", "parcosim", "kernels")
#: Test files no mutant runs: the mutation tools' own, and the sanitizer build of pristine C.
NOT_RUN = mutation_map.NOT_RUN
#: How many imports away a test file may reach a module and still count as importing it (a
#: package's ``__init__`` names all its modules, so the full closure is nearly every test).
NEAR = 2


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


#: Calls whose first argument names a process: a mutant of it (``0`` -> ``1``, another local) would act on
#: another process of the machine (the campaigns run as root: PID 1 pinned to one core, a kill).
PROCESS_CALLS = {"os.kill", "os.killpg", "os.sched_setaffinity", "os.setpgid", "os.setpriority", "os.waitpid"}


def _skipped(tree) -> set:
    """ids of nodes never mutated: docstrings, annotations, f-strings and what they hold, and the
    process argument of :data:`PROCESS_CALLS`."""
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
        elif isinstance(node, ast.Call) and node.args and ast.unparse(node.func) in PROCESS_CALLS:
            mark(node.args[0])
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


def importers(root: Path = ROOT) -> dict:
    """Product module -> the test files of ``root`` (a campaign's copy of its commit) that
    import it, or import a module that imports it (:data:`NEAR` imports away at most); never
    a file of :data:`NOT_RUN`."""
    graph = {}
    for path in [root / f for f in python_files()] + sorted((root / "tests").rglob("*.py")):
        own = module_name(str(path.relative_to(root)))
        graph[own] = _imports(path, own)
    mapping = {}
    for test in sorted((root / "tests").rglob("test_*.py")):
        if str(test.relative_to(root)).startswith(NOT_RUN):
            continue
        seen, frontier = set(), set(graph[module_name(str(test.relative_to(root)))])
        for _ in range(NEAR):
            frontier -= seen
            seen |= frontier
            frontier = {n for m in frontier for n in graph.get(m, ())}
        for m in seen:
            mapping.setdefault(m, []).append(str(test.relative_to(root)))
    return mapping


def main(argv=None) -> int:
    from benchmarks.mutation_report import table
    from benchmarks import mutation_run
    from benchmarks.mutation_run import campaign, confirm, read_results, rerun, results_path

    parser = argparse.ArgumentParser(prog="python -m benchmarks.mutation_py", description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=3501)
    parser.add_argument("--sample", type=int, default=300)
    parser.add_argument("--base", type=float, default=30.0, help="CPU seconds a test run may take besides its tests'")
    parser.add_argument("--factor", type=float, default=3.0,
                        help="a run's CPU-time limit in multiples of its tests' measured seconds (plus --base)")
    parser.add_argument("--budget", type=float, default=300.0,
                        help="measured seconds of tests a mutant runs at most (the cheapest first)")
    parser.add_argument("--retry-timeouts", action="store_true", help="run the timed-out mutants again, last")
    parser.add_argument("--workers", type=int, default=1, help="mutants run at once (one tree copy each)")
    parser.add_argument("--results", type=Path, help="the JSON-lines file (default: benchmarks/results/mutation_<seed>.jsonl)")
    parser.add_argument("--report", action="store_true", help="reprint the table from --results")
    parser.add_argument("--confirm", action="store_true", help="re-run the killing tests on the unmutated tree")
    parser.add_argument("--pool", action="store_true", help="list every mutant of the pool")
    parser.add_argument("--rerun-survivors", type=Path, metavar="FROM",
                        help="run FROM's survived and timed-out mutants again with today's selection into "
                             "--results (a new file; the killed ones copied as they are; resumes)")
    parser.add_argument("--language", choices=("c", "python"),
                        help="with --rerun-survivors: re-run this language's mutants only (the others carried)")
    parser.add_argument("--outcomes", nargs="+", choices=mutation_run.RERUN, default=mutation_run.RERUN,
                        help="with --rerun-survivors: re-run the mutants of these outcomes only")
    parser.add_argument("--c-test-files", nargs="+", metavar="GLOB",
                        help="the test files a C mutant's selection draws from (default: every test file)")
    parser.add_argument("--wall-factor", type=float, default=mutation_run.WALL_FACTOR,
                        help="a run's wall-clock limit in multiples of its CPU-time limit (a test that "
                             "waits on a hung child uses no CPU; lower it on cores nobody else uses)")
    args = parser.parse_args(argv)
    mutation_run.C_TESTS = tuple(args.c_test_files or ())
    mutation_run.WALL_FACTOR = args.wall_factor
    results = args.results or results_path(args.seed)
    if args.pool:
        for name, mutants in pool_by_file().items():
            for m in mutants:
                print(f"{name}:{m.line}:{m.column} {m.operator} {m.before[:60]!r} -> {m.after[:60]!r}")
        return 0
    if args.rerun_survivors:
        if not args.results:
            parser.error("--rerun-survivors needs --results NEW.jsonl (the file re-run is kept as it is)")
        rerun(args.rerun_survivors, results, args.workers, args.base, args.factor, args.budget, args.language,
              tuple(args.outcomes))
    elif args.confirm:
        print(confirm(results, 90.0))
    elif not args.report:
        campaign(args.seed, args.sample, args.workers, results, args.retry_timeouts, args.base, args.factor,
                 args.budget)
    print(table(*read_results(results)))
    return 0


if __name__ == "__main__":
    sys.exit(main())

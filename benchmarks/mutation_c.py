"""Mutation testing of parcosim's C kernels (``kernels/src/*.c``), out of sample (issue 31).

cosmic-ray (``benchmarks/mutation.py``) mutates Python only; every model's numerical step is
C now.  This tool enumerates one-line mutants of the ``.c`` files, draws a seeded sample
uniformly over the pool (so each file is weighted by its share of the pool), builds each
mutant into its own library and runs the kernel tests against it through
``$PARCOSIM_KERNELS_LIB``.  A mutant that does not compile (``-Werror`` included) is "not
viable", counted apart from killed and survived; a test run over its time limit (a hang)
counts as killed and is marked so.

    python -m benchmarks.mutation_c --seed 31 --sample 100   # run, write the JSON, print the table
    python -m benchmarks.mutation_c --report                  # the table again, from the JSON

Operators (token level, one line at a time; comments, string literals, preprocessor lines
and ``PC_FIELD`` lists are never mutated):

``arith``      binary ``+`` <-> ``-``, ``*`` <-> ``/`` (compound assignments included)
``compare``    ``<`` <-> ``<=``, ``>`` <-> ``>=``, ``==`` <-> ``!=``
``constant``   a non-zero number times 2, ``0`` <-> ``1`` (``0.0`` -> ``1.0``)
``drop``       ``a + b`` -> ``a`` (also ``-``) when ``b`` is a simple operand
``swap``       two adjacent arguments of a call, or two indices ``[i][j]`` -> ``[j][i]``
"""
from __future__ import annotations

import argparse
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from kernels import build as kbuild

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "mutation_c.json"
TESTS = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "tests" / "kernels").glob("test_kernels_*.py"))
#: the compiled co-simulation loop (loop.c) is exercised by the compiled-loop tests too
EXTRA_TESTS = {"loop.c": ["tests/fmus/cosim/test_compiled.py"]}

_IDENT = r"[A-Za-z_]\w*"
_NUMBER = re.compile(r"(?<![\w.])(\d+\.\d*|\.\d+|\d+)([eE][+-]?\d+)?([fFuUlL]*)(?![\w.])")
_TYPES = {"double", "int", "char", "void", "const", "size_t", "unsigned", "long", "float", "static", "struct"}
_NOT_CALLS = {"if", "for", "while", "switch", "return", "sizeof"}
_OPERAND_END = re.compile(r"[\w)\]]$")
_SIMPLE_OPERAND = re.compile(rf"\s*(?:{_IDENT}(?:(?:->|\.){_IDENT})*|\d+\.?\d*(?:[eE][+-]?\d+)?|\.\d+)")


@dataclass(frozen=True)
class Mutant:
    """One change: in ``file`` (a name in the sources folder), line ``line`` (1-based), the
    text ``before`` at column ``column`` becomes ``after``."""

    file: str
    line: int
    column: int
    operator: str
    before: str
    after: str

    def apply(self, text: str) -> str:
        """``text`` (the whole file) with this change."""
        lines = text.split("\n")
        row = lines[self.line - 1]
        if row[self.column:self.column + len(self.before)] != self.before:
            raise ValueError(f"{self.file}:{self.line}: {self.before!r} is not at column {self.column}")
        lines[self.line - 1] = row[:self.column] + self.after + row[self.column + len(self.before):]
        return "\n".join(lines)


def masked_lines(text: str) -> list:
    """The lines of C ``text`` with comments and string/char literal contents blanked (same
    columns), so operators never see them."""
    out, in_block = [], False
    for line in text.split("\n"):
        chars, i = list(line), 0
        while i < len(chars):
            pair = line[i:i + 2]
            if in_block:
                if pair == "*/":
                    chars[i] = chars[i + 1] = " "
                    in_block, i = False, i + 2
                    continue
                chars[i] = " "
            elif pair == "/*":
                chars[i] = chars[i + 1] = " "
                in_block, i = True, i + 2
                continue
            elif pair == "//":
                chars[i:] = " " * (len(chars) - i)
                break
            elif line[i] in "\"'":
                end = _literal_end(line, i)
                chars[i + 1:end] = " " * (end - i - 1)
                i = end
            i += 1
        out.append("".join(chars))
    return out


def _literal_end(line: str, start: int) -> int:
    """Index of the quote closing the literal opened at ``start``."""
    i = start + 1
    while i < len(line) and line[i] != line[start]:
        i += 2 if line[i] == "\\" else 1
    return min(i, len(line) - 1)


def mutable(code: str) -> bool:
    """Whether a masked line may be mutated: not blank, not preprocessor, not a field list."""
    stripped = code.strip()
    return bool(stripped) and not stripped.startswith("#") and "PC_FIELD" not in code


def _binary(code: str, i: int) -> bool:
    """Whether the operator at ``i`` has an operand just before it (so it is binary), and
    that operand is not a type name (``double *p`` is a declaration)."""
    before = code[:i].rstrip()
    if not _OPERAND_END.search(before):
        return False
    word = re.search(r"\w+$", before)
    return not (word and (word.group() in _TYPES or re.fullmatch(r"pc_\w+", word.group())))


def arith(code: str):
    """``+``/``-`` and ``*``/``/`` swapped where binary (``++``, ``--``, ``->`` excluded)."""
    swap = {"+": "-", "-": "+", "*": "/", "/": "*"}
    for i, c in enumerate(code):
        if c not in swap:
            continue
        near = code[i - 1:i] + code[i + 1:i + 2]
        if c in "+-" and (c in near or code[i:i + 2] == "->") or c in "*/" and ("*" in near or "/" in near):
            continue
        if _binary(code, i):
            yield i, c, swap[c]


def compare(code: str):
    """``<``/``<=``, ``>``/``>=``, ``==``/``!=`` swapped (shifts and ``->`` excluded)."""
    for m in re.finditer(r"(?<![<>=!-])(<=|>=|==|!=|<|>)(?![<>=])", code):
        op = m.group(1)
        yield m.start(), op, {"<": "<=", "<=": "<", ">": ">=", ">=": ">", "==": "!=", "!=": "=="}[op]


def constant(code: str):
    """A non-zero number doubled; ``0`` <-> ``1`` (``0.0`` -> ``1.0``)."""
    for m in _NUMBER.finditer(code):
        digits, exponent, suffix = m.group(1), m.group(2) or "", m.group(3)
        is_float = "." in digits or bool(exponent)
        value = float(digits + exponent) if is_float else int(digits)
        if not is_float:
            new = {0: "1", 1: "0"}.get(value, str(value * 2))
        elif value == 0:
            new = "1.0"
        else:
            new = repr(value * 2)
        yield m.start(), m.group(), new + suffix


def drop(code: str):
    """``a + b`` -> ``a`` (and ``-``) when ``b`` is a simple operand not bound tighter by what
    follows it (``*``, ``/``, a call, an index or a member)."""
    for i, _, _ in arith(code):
        if code[i] not in "+-" or code[i + 1:i + 2] == "=":
            continue
        operand = _SIMPLE_OPERAND.match(code, i + 1)
        if not operand:
            continue
        rest = code[operand.end():].lstrip()
        if rest[:1] in ("*", "/", "(", "[", ".", "%") or rest[:2] == "->":
            continue
        start = len(code[:i].rstrip())
        yield start, code[start:operand.end()], ""


def swap(code: str):
    """Two adjacent arguments of a call (flat argument lists only), or two indices ``[i][j]``."""
    for m in re.finditer(rf"\b({_IDENT})\s*\(([^()]*)\)", code):
        if m.group(1) in _NOT_CALLS:
            continue
        args = m.group(2).split(",")
        for k in range(len(args) - 1):
            left, right = args[k], args[k + 1]
            if left.strip() and right.strip() and left.strip() != right.strip():
                swapped = args[:k] + [_keep_space(left, right), _keep_space(right, left)] + args[k + 2:]
                yield m.start(2), m.group(2), ",".join(swapped)
    for m in re.finditer(r"\[([^\[\]]+)\]\s*\[([^\[\]]+)\]", code):
        if m.group(1).strip() != m.group(2).strip():
            yield m.start(), m.group(), f"[{m.group(2)}][{m.group(1)}]"


def _keep_space(slot: str, text: str) -> str:
    """``text``'s content in ``slot``'s surrounding whitespace."""
    lead = slot[:len(slot) - len(slot.lstrip())]
    trail = slot[len(slot.rstrip()):]
    return lead + text.strip() + trail


OPERATORS = {"arith": arith, "compare": compare, "constant": constant, "drop": drop, "swap": swap}


def mutants_of(name: str, text: str) -> list:
    """Every mutant of one C file's ``text``; ``name`` labels them."""
    found = []
    for number, code in enumerate(masked_lines(text), start=1):
        if not mutable(code):
            continue
        for operator, generate in OPERATORS.items():
            for column, before, after in generate(code):
                found.append(Mutant(name, number, column, operator, before, after))
    return found


def pool(sources: Path = kbuild.SOURCES) -> list:
    """The mutants of every ``.c`` file in ``sources``, in file and line order."""
    return [m for path in sorted(sources.glob("*.c")) for m in mutants_of(path.name, path.read_text())]


def build_from(sources: Path, out: Path) -> Path:
    """:func:`kernels.build.build`'s compile of the ``.c`` files in ``sources`` (same compiler
    and flags; the identity hash is the pristine sources', so the library passes for the real
    one) into ``out``.  Raises ``subprocess.CalledProcessError`` when the compiler refuses."""
    files = sorted(str(p) for p in sources.glob("*.c"))
    subprocess.run([kbuild.compiler(), *kbuild.FLAGS, f'-DPC_SOURCES_HASH="{kbuild.sources_hash()}"',
                    f"-I{sources}", *files, "-o", str(out), "-lm"],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return out


def run_mutant(mutant: Mutant, timeout: float) -> dict:
    """Build ``mutant`` and run its tests: a record with ``outcome`` killed, survived,
    not viable, or killed with ``timeout`` true."""
    work = Path(tempfile.mkdtemp(prefix="parcosim_cmut_"))
    try:
        sources = work / "src"
        shutil.copytree(kbuild.SOURCES, sources)
        target = sources / mutant.file
        target.write_text(mutant.apply(target.read_text()))
        try:
            library = build_from(sources, work / kbuild.LIBRARY.name)
        except subprocess.CalledProcessError:
            return {"outcome": "not viable", "timeout": False, "seconds": 0.0}
        tests = TESTS + EXTRA_TESTS.get(mutant.file, [])
        env = dict(os.environ, PARCOSIM_KERNELS_LIB=str(library))
        start = time.monotonic()
        try:
            done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", *tests],
                                  cwd=ROOT, env=env, timeout=timeout, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            return {"outcome": "killed", "timeout": True, "seconds": timeout}
        outcome = "survived" if done.returncode == 0 else "killed"
        return {"outcome": outcome, "timeout": False, "seconds": round(time.monotonic() - start, 1),
                "returncode": done.returncode}
    finally:
        shutil.rmtree(work, ignore_errors=True)


def campaign(seed: int, sample: int, timeout: float, results: Path) -> dict:
    """Draw ``sample`` mutants with ``seed`` and run them, writing ``results`` after each."""
    everything = pool()
    chosen = random.Random(seed).sample(everything, min(sample, len(everything)))
    per_file = {}
    for m in everything:
        per_file[m.file] = per_file.get(m.file, 0) + 1
    record = {"seed": seed, "sample": len(chosen), "pool": per_file, "tests": TESTS, "extra_tests": EXTRA_TESTS,
              "timeout_seconds": timeout, "mutants": []}
    for k, mutant in enumerate(chosen, start=1):
        result = run_mutant(mutant, timeout)
        record["mutants"].append({**asdict(mutant), **result})
        print(f"[{k}/{len(chosen)}] {mutant.file}:{mutant.line} {mutant.operator} "
              f"{mutant.before!r} -> {mutant.after!r}: {result['outcome']}", flush=True)
        results.parent.mkdir(parents=True, exist_ok=True)
        results.write_text(json.dumps(record, indent=1) + "\n")
    return record


def table(record: dict) -> str:
    """The per-file score (markdown) and the survivors."""
    rows = ["| file | pool | sampled | killed | survived | not viable |", "|---|---|---|---|---|---|"]
    totals = [0, 0, 0, 0, 0]
    for name in sorted(record["pool"]):
        mine = [m for m in record["mutants"] if m["file"] == name]
        counts = [record["pool"][name], len(mine)] + [sum(m["outcome"] == o for m in mine)
                                                      for o in ("killed", "survived", "not viable")]
        totals = [a + b for a, b in zip(totals, counts)]
        rows.append(f"| kernels/src/{name} | " + " | ".join(map(str, counts)) + " |")
    viable = totals[2] + totals[3]
    score = f"{totals[2]} ({100 * totals[2] / viable:.0f} % of viable)" if viable else "0"
    rows.append(f"| **total** | {totals[0]} | {totals[1]} | **{score}** | {totals[3]} | {totals[4]} |")
    hangs = [m for m in record["mutants"] if m.get("timeout")]
    rows.append(f"\nkilled by a hang (over {record['timeout_seconds']:.0f} s): {len(hangs)}")
    rows.append("\nsurvivors:")
    rows += [f"- {m['file']}:{m['line']}:{m['column']} ({m['operator']}) {m['before']!r} -> {m['after']!r}"
             for m in record["mutants"] if m["outcome"] == "survived"]
    return "\n".join(rows)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.mutation_c", description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=31)
    parser.add_argument("--sample", type=int, default=100, help="mutants drawn from the pool")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds a test run may take (a hang: killed)")
    parser.add_argument("--results", type=Path, default=RESULTS)
    parser.add_argument("--report", action="store_true", help="reprint the table from --results")
    parser.add_argument("--pool", action="store_true", help="list every mutant of the pool (file:line:column)")
    args = parser.parse_args(argv)
    if args.pool:
        for m in pool():
            print(f"{m.file}:{m.line}:{m.column} {m.operator} {m.before!r} -> {m.after!r}")
        return 0
    record = json.loads(args.results.read_text()) if args.report else campaign(
        args.seed, args.sample, args.timeout, args.results)
    print(table(record))
    return 0


if __name__ == "__main__":
    sys.exit(main())

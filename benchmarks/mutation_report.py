"""The tables of a :mod:`benchmarks.mutation_py` campaign: per area, per operator, the
survivors.  Score = killed / (killed + survived); ``timeout`` is undecided and counted apart.
The kills are counted by kind (``killed_by``: a failing test, or a loud failure of the run:
collection, crash, internal error; none recorded: a campaign before session 41).
"""
from __future__ import annotations

from collections import Counter

#: fmus/ modules of the FMI layer's export, SSP, state and refusal code (issue 31 item 2).
FMI_EXPORT = ("archive", "build", "bundle", "designs", "export", "fmustate", "foreign", "guarded", "identity",
              "modeldescription", "refusals", "slavestate", "ssp", "ssp_run", "stateformat")
#: The same modules since the layout of issue 29 (fmus/__init__.py's MOVED), by path.
FMI_EXPORT_FILES = ("fmus/export/archive.py", "fmus/export/build.py", "fmus/export/bundle.py",
                    "fmus/slave/designs.py", "fmus/systemfmu/export.py", "fmus/slave/state.py",
                    "fmus/cosim/foreign.py", "fmus/slave/base.py", "fmus/slave/identity.py",
                    "fmus/export/modeldescription.py", "fmus/slave/refusals.py", "fmus/slave/state_calls.py",
                    "fmus/ssp/__init__.py", "fmus/ssp/export.py", "fmus/ssp/run.py", "fmus/slave/state_format.py")
#: controller/ modules of the control law and its gains.
LAW = ("law", "position", "strategies")
AREAS = ("kernels C", "law", "controller", "plant", "motor", "fmus export/SSP/state/refusals", "fmus other",
         "scenarios", "kernels, parcosim (Python)")


def area(name: str) -> str:
    """The area a file counts in."""
    top, _, rest = name.partition("/")
    stem = rest.rsplit("/", 1)[-1].removesuffix(".py")
    if name.startswith("kernels/src/"):
        return "kernels C"
    if top == "controller":
        return "law" if stem in LAW else "controller"
    if top == "fmus":
        exported = name in FMI_EXPORT_FILES or "/" not in rest and stem in FMI_EXPORT
        return "fmus export/SSP/state/refusals" if exported else "fmus other"
    if top in ("kernels", "parcosim"):
        return "kernels, parcosim (Python)"
    return top


def table(header: dict, done: dict) -> str:
    """The campaign's tables (markdown) from :func:`benchmarks.mutation_py.read_results`."""
    ran = list(done.values())
    rows = [f"seed {header['seed']}, commit {header['commit'][:10]}, {len(ran)} of {header['sample']} run",
            "", "| area | lines | drawn | run | killed | survived | not viable | timeout | score |",
            "|---|---|---|---|---|---|---|---|---|"]
    for a in AREAS + ("**total**",):
        every = a == "**total**"
        mine = [m for m in ran if every or area(m["file"]) == a]
        lines = sum(v for n, v in header["lines"].items() if every or area(n) == a)
        drawn = sum(every or area(n) == a for n in header["drawn"]) if header["drawn"] else "-"
        counts = [sum(m["outcome"] == o for m in mine) for o in ("killed", "survived", "not viable", "timeout")]
        k, s = counts[0], counts[1]
        score = f"{100 * k / (k + s):.1f} %" if k + s else "-"
        rows.append(f"| {a} | {lines} | {drawn} | {len(mine)} | " + " | ".join(map(str, counts)) + f" | {score} |")
    rows.append("\noperators (killed / killed + survived): " + ", ".join(
        f"{op} {sum(m['outcome'] == 'killed' for m in ran if m['operator'] == op)}/"
        f"{sum(m['outcome'] in ('killed', 'survived') for m in ran if m['operator'] == op)}"
        for op in sorted({m["operator"] for m in ran})))
    selections = {}
    for m in ran:
        selections[m.get("selection", "-")] = selections.get(m.get("selection", "-"), 0) + 1
    rows.append("selection: " + ", ".join(f"{k} {v}" for k, v in sorted(selections.items())))
    seconds = sum(m.get("seconds", 0.0) for m in ran)
    rows.append(f"wall seconds of the runs: {seconds:.0f} ({seconds / max(1, len(ran)):.1f} a mutant)")
    kinds = Counter(m.get("killed_by", "not recorded") for m in ran if m["outcome"] == "killed")
    rows.append("kills by kind: " + ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())))
    other = [m for m in ran if m["outcome"] in ("error", "baseline failure")]
    if other:
        rows.append(f"\nerror / baseline failure: {len(other)}")
    rows.append("\nsurvivors:")
    rows += [f"- [{m['index']}] {m['file']}:{m['line']}:{m['column']} ({m['operator']}) {m['before'][:80]!r} -> "
             f"{m['after'][:80]!r}" + (f" [{m['note']}]" if m.get("note") else f" [{m.get('selected')} tests]")
             for m in sorted(ran, key=lambda m: m["index"]) if m["outcome"] == "survived"]
    return "\n".join(rows)

"""The long hostile-use campaign (issue 13): thousands of cases through fmpy, a summary table.

    python -m fmus.hostile.campaign --cases 3000 [--fmu-dir DIR] [--out out/hostile] [--seed 0]
    python -m fmus.hostile.campaign --native --cases 3000 [--fmu-dir DIR] [--loop LOOP.fmu]   # issue 28

Runs ``--cases`` cases (spread evenly over the FMUs, every kind in turn) from
:func:`fmus.hostile.cases.make_case` in worker subprocesses (:func:`fmus.hostile.cases.run_cases`),
then writes ``summary.md`` (outcome counts per FMU and kind: the table of docs/extremes.md),
``cases.jsonl`` (every case with its outcome, statuses and problems: a failing case can be
replayed from it) and prints the summary.  Exit status 1 if any case crashed, hung, returned
fmi2Fatal or broke a property.

With ``--native`` the FMUs are parcosim's native ones (of ``--fmu-dir``, or built with
``parcosim build --native``), each compiled again from its own sources with
``-fsanitize=address,undefined`` and driven with the sanitizers' runtime
(:func:`fmus.hostile.cases.sanitizer_env`; their reports go to ``OUT/sanitizer``), every
kind of case; ``--no-sanitize`` drives the FMUs as built; ``--loop LOOP.fmu`` adds a
scene's whole loop as one native FMU (written by ``parcosim export-fmu SCENE LOOP.fmu --native``),
``--models ClosedLoop`` alone.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from fmus.hostile import cases as hostile


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fmus.hostile.campaign", description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=3000, help="number of cases (default 3000)")
    parser.add_argument("--fmu-dir", default=None, help="the built FMUs (default: built into a temporary directory)")
    parser.add_argument("--out", default="out/hostile", help="where summary.md and cases.jsonl go")
    parser.add_argument("--seed", type=int, default=0, help="first case seed (default 0)")
    parser.add_argument("--batch", type=int, default=30, help="cases per worker process (default 30)")
    parser.add_argument("--models", default=None, help="comma-separated FMUs (default: all)")
    parser.add_argument("--native", action="store_true",
                        help="parcosim's native FMUs, rebuilt with AddressSanitizer and UBSan (issue 28)")
    parser.add_argument("--no-sanitize", action="store_true", help="with --native: the FMUs as built")
    parser.add_argument("--loop", default=None, metavar="LOOP.fmu",
                        help="with --native: also this native ClosedLoop (parcosim export-fmu SCENE LOOP.fmu --native)")
    args = parser.parse_args(argv)

    work = Path(tempfile.mkdtemp(prefix="parcosim-hostile-"))
    env = None
    if args.native:
        sanitize = not args.no_sanitize
        unzipped = hostile.prepared_native_fmus(args.fmu_dir, args.models, work, sanitize=sanitize,
                                                loop_fmu=args.loop)
        env = hostile.sanitizer_env(Path(args.out) / "sanitizer") if sanitize else None
        wrapper = {model: hostile.is_native(path) for model, path in unzipped.items()}
    else:
        if args.loop:
            parser.error("--loop goes with --native")
        unzipped = hostile.prepared_fmus(args.fmu_dir, args.models, work)
        wrapper = {model: hostile.wrapper_is_ours(path, model) for model, path in unzipped.items()}
    per_model = -(-args.cases // len(unzipped))
    cases = []
    for model, path in unzipped.items():
        kinds = [k for k in hostile.KINDS if wrapper[model] or k not in hostile.WRAPPER_KINDS]
        cases += hostile.cases_for(model, path, range(args.seed, args.seed + per_model), wrapper=wrapper[model],
                                   kinds=kinds)
    start = time.perf_counter()
    done = [0]

    def progress(result):
        done[0] += 1
        if done[0] % 100 == 0 or result.outcome not in hostile.ANSWERED:
            print(f"{done[0]}/{len(cases)} {time.perf_counter() - start:.0f} s"
                  + ("" if result.outcome in hostile.ANSWERED else
                     f"  {result.outcome}: {result.case['model']} {result.case['kind']} seed {result.case['seed']} "
                     f"{result.problems[:1]}"), file=sys.stderr, flush=True)

    results = hostile.run_cases(cases, unzipped, batch=args.batch, progress=progress, env=env)
    wall = time.perf_counter() - start
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "cases.jsonl", "w", encoding="utf-8") as f:
        for r in results:
            f.write(json.dumps({"case": r.case, "outcome": r.outcome, "problems": r.problems,
                                "statuses": r.statuses, "seconds": r.seconds}) + "\n")
    binaries = ", ".join(sorted({"parcosim's FMI wrapper" if w else "pythonfmu 0.7's binary" for w in wrapper.values()}))
    if args.native:
        binaries = "native FMUs" + (", rebuilt with -fsanitize=address,undefined" if env else "")
    text = (f"{len(results)} cases, {wall:.0f} s wall ({binaries}); "
            f"`python -m fmus.hostile.campaign{' --native' if args.native else ''}"
            f"{f' --loop {args.loop}' if args.loop else ''} --cases {args.cases} --seed {args.seed}`\n\n"
            + hostile.markdown_summary(results) + "\n")
    (out / "summary.md").write_text(text, encoding="utf-8")
    print(text)
    bad = [r for r in results if r.outcome not in hostile.ANSWERED]
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())

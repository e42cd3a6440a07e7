"""Out-of-sample mutation sample of the FMU-state and call-budget modules (issue 30; docs/mutation.md).

    git worktree add --detach /work/wtS <commit> && cd /work/wtS
    PYTHONPATH=$PWD python -m benchmarks.mutation_state [--report]

30 mutants drawn (seed 30) from fmus/slave/state_format.py, fmus/slave/state.py, fmus/slave/state_calls.py and
fmus/slave/budget.py with :mod:`benchmarks.mutation`'s machinery, run against their test modules
before any test is written for what the sample finds (the score is out of sample).
"""
import os
import subprocess
import sys

import benchmarks.mutation as m

FILES = ("fmus/slave/state_format.py", "fmus/slave/state.py", "fmus/slave/state_calls.py", "fmus/slave/budget.py")
#: Source -> its test modules (those of the campaign's :data:`benchmarks.mutation.TARGETS`).
TARGETS = {source: m.TARGETS[source] for source in FILES}
WORKDIR = m.ROOT / "out" / "mutation30"
SAMPLE, SEED = 30, 30


def execute(workdir):
    """Run the pending mutants of :data:`TARGETS` (as :func:`benchmarks.mutation.execute`, JIT on)."""
    env = dict(os.environ, PYTHONPATH=str(m.ROOT))
    m._restore_sources(workdir)
    for source in m.TARGETS:
        print(f"== {source}", flush=True)
        (workdir / f"current.{m.ROOT.name}").write_text(source)
        subprocess.run(["cosmic-ray", "exec", str(m._config(workdir, source)), str(m._session(workdir, source))],
                       cwd=m.ROOT, env=env, check=False)
        m._restore_sources(workdir)


def main(argv) -> int:
    m.TARGETS, m.LAW = TARGETS, {}   # the campaign's machinery on these files alone
    if "--report" not in argv:
        m.initialise(WORKDIR, SAMPLE, SEED)
        execute(WORKDIR)
    m.print_report(m.report(WORKDIR))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

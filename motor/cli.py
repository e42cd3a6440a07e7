"""Command ``parcosim identify-motor``: appendix-D identification of a CSV file."""

import argparse
import json
import sys

from motor.identification import DATASHEET_KT_OVER_KE, MEASURED_L, identify, read_motor_csv


class _UsageError(Exception):
    """Raised instead of argparse's multi-line usage error."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise _UsageError(message)


def _parser():
    p = _Parser(prog="parcosim identify-motor",
                description="Identify DC motor parameters (thesis appendix D) from steady-state "
                            "data and print them as JSON (SI units).")
    p.add_argument("--data", required=True, metavar="FILE.csv",
                   help="CSV with a header and columns u [V], i [A], omega [rad/s] (omega > 0)")
    p.add_argument("--kt-over-ke", type=float, default=DATASHEET_KT_OVER_KE, metavar="RATIO",
                   help=f"datasheet ratio kt'/ke' of (D.6) (default {DATASHEET_KT_OVER_KE:.7g})")
    p.add_argument("--settling-time", type=float, default=None, metavar="S",
                   help="t_98%% of the speed step response [s] (D.15); adds J to the output")
    p.add_argument("--inductance", type=float, default=MEASURED_L, metavar="H",
                   help=f"armature inductance used by (D.16) [H] (default {MEASURED_L})")
    return p


def identify_main(argv=None):
    """Run ``parcosim identify-motor`` with arguments ``argv``.

    Parameters
    ----------
    argv : list of str, optional
        Arguments after ``identify-motor``; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success (JSON on stdout); 2 on a bad argument, file, column or
        value, with one line ``parcosim identify-motor: error: ...`` on stderr.
    """
    try:
        args = _parser().parse_args(argv)
        u, i, omega = read_motor_csv(args.data)
        result = identify(u, i, omega, kt_over_ke=args.kt_over_ke,
                          settling_time=args.settling_time, L=args.inductance)
    except (_UsageError, ValueError) as exc:
        print(f"parcosim identify-motor: error: {exc}", file=sys.stderr)
        return 2
    except SystemExit as exc:  # --help
        return exc.code or 0
    print(json.dumps(result, indent=2))
    return 0

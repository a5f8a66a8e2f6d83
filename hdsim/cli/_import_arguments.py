"""The import options of ``fit`` and ``diagnose``: a bench log read as it was written.

docs/measurements.md, "Bringing your own bench log", shows them on real-looking logs.
"""

from __future__ import annotations

import re

IMPORT_EPILOG = """\
reading a log from other bench software (nothing needs editing):
  --test stiffness --ratio 100 --rated-torque 67   the '#' keys the log lacks
  --columns time_s=t,torque_Nm=5.11*iq_A,angle_rev=pos
                                 map and scale columns: FACTOR*column (e.g. torque from
                                 motor current), angle units _rad _deg _arcmin _arcsec _rev
  --drop-nan                     drop rows with a NaN or empty cell, or a one-row glitch (counted)
  --window 2.5:40                keep 2.5 s <= time_s <= 40 s
  --concatenated                 several runs whose clock restarts: joined end to end
  --sample-rate 1                a log without a time column (a step test point by point):
                                 time = row / rate
  --test running_torque --ratio 100 --meta torque_side=output
                                 a friction sweep whose torque is on the output shaft
"""


def add_record_parser(subparsers, verb: str, help_text: str, effects_help: str):
    """The parser of a verb that reads a bench log: DATA, ``--effects``, ``--unit`` and the
    import options (`add_import_arguments`); the verb adds its own options to it."""
    import argparse

    p = subparsers.add_parser(verb, help=help_text, description=help_text + ".", epilog=IMPORT_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("data", metavar="DATA", help="measurement file (CSV or HDF5; see docs/measurements.md)")
    p.add_argument("--effects", default="", help=effects_help)
    p.add_argument("--unit", default=None,
                   help="built-in unit or drive file (TOML, see 'hdsim units --template') to start from "
                        "(default CSG-25-100)")
    add_import_arguments(p)
    return p


def add_import_arguments(parser) -> None:
    """Add the import options (contracts of the measurement files, section 1a) to a verb."""
    group = parser.add_argument_group("reading the log (see the notes below)")
    group.add_argument("--columns", default=None, metavar="MAP",
                       help="column map for another bench, e.g. time_s=t,torque_Nm=5.11*iq_A,angle_deg=pos")
    # no argparse choices: the reader checks the name against every registered test kind
    # (a plug-in's too) and names the close ones
    group.add_argument("--test", default=None, metavar="TEST",
                       help="the test the log holds (sets '# test'): stiffness, kinematic_error, running_torque, "
                            "breakaway, or a registered kind")
    group.add_argument("--ratio", default=None, type=float, metavar="N", help="transmission ratio (sets '# ratio')")
    group.add_argument("--rated-torque", default=None, type=float, metavar="T_N",
                       help="rated torque [N·m] (sets '# rated_torque_Nm')")
    group.add_argument("--meta", action="append", default=[], metavar="KEY=VALUE",
                       help="set any other '#' key, e.g. torque_side=output (repeatable)")
    group.add_argument("--drop-nan", action="store_true",
                       help="drop rows with a non-finite or empty cell in a used column, or a one-row "
                            "glitch (counted)")
    group.add_argument("--window", default=None, metavar="T0:T1", help="keep rows with T0 <= time_s <= T1 [s]")
    group.add_argument("--concatenated", action="store_true",
                       help="the log holds several runs whose clock restarts: join them end to end")
    group.add_argument("--sample-rate", default=None, type=float, metavar="HZ",
                       help="a log without a time column: time_s = row index / HZ")


#: the library names an import option by its keyword (``drop_nan=True``, ``sample_rate=HZ``,
#: ``columns={'time_s': NAME}``, ``ratio: …`` at the start); the command line says the flag
_KEYWORDS = "test|ratio|rated_torque|meta|drop_nan|window|sample_rate|concatenated"
_CLI_WORDS = (
    (re.compile(r"(?<![\w/.-])(drop_nan|concatenated)=True\b"), lambda m: _flag(m[1])),
    (re.compile(r"(?<![\w/.-])columns=\{'(\w+)': '?([^'}]+?)'?\}"), lambda m: f"--columns {m[1]}={m[2]}"),
    (re.compile(r"(?<![\w/.-])(test|ratio|rated_torque|sample_rate)=(\w+)"), lambda m: f"{_flag(m[1])} {m[2]}"),
    (re.compile(rf"^({_KEYWORDS}): "), lambda m: f"{_flag(m[1])}: "),
)


def _flag(keyword: str) -> str:
    return "--" + keyword.replace("_", "-")


def cli_words(message: str) -> str:
    """A library message about the import options in the command line's words (the flags)."""
    for pattern, flag in _CLI_WORDS:
        message = pattern.sub(flag, message)
    return message


def import_options(args):
    """The `hdsim.io.import_options.ImportOptions` of parsed arguments (InputError on bad strings)."""
    from hdsim.io.import_options import ImportOptions, parse_meta, parse_window

    return ImportOptions(test=args.test, ratio=args.ratio, rated_torque=args.rated_torque,
                         meta=parse_meta(args.meta), drop_nan=args.drop_nan,
                         window=parse_window(args.window) if args.window else None,
                         sample_rate=args.sample_rate, concatenated=args.concatenated)

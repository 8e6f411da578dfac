"""The generator's command line, mounted by fosmodel as ``fosmodel synth``.

``fosmodel synth SCENARIO --duration S --rate HZ --seed N --out FILE.csv``
writes ``FILE.csv`` and ``FILE.truth.json``, or for a scenario of several
sessions ``FILE_s1.csv``, ``FILE_s1.truth.json``, ... one pair per session;
``--list`` prints the scenarios.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence

from data_synth.io import write_record, write_sessions
from data_synth.scenarios import SCENARIOS, make_sessions
from fosmodel.core.exceptions import InputError


def configure_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the ``synth`` arguments to ``parser`` and return it."""
    parser.add_argument("scenario", nargs="?", help="scenario name (see --list)")
    parser.add_argument("--list", action="store_true", help="list the scenarios and exit")
    parser.add_argument("--duration", type=float, metavar="S",
                        help="length in seconds (default: the scenario's, see --list)")
    parser.add_argument("--rate", type=float, metavar="HZ",
                        help="sampling rate in Hz (default: the scenario's, see --list)")
    parser.add_argument("--seed", type=int, default=0, metavar="N", help="random seed")
    parser.add_argument(
        "--out", metavar="FILE.csv", help="output CSV; the truth goes to FILE.truth.json"
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="scenario parameter, VALUE read as JSON if it parses (e.g. rho_arw=-0.1)",
    )
    parser.add_argument("--no-time", action="store_true", help="do not write the time column")
    return parser


def run(args: argparse.Namespace) -> int:
    """Execute parsed ``synth`` arguments; return the exit status.

    Raises
    ------
    fosmodel.core.exceptions.InputError
        Unknown scenario or parameter, missing ``--out``, unusable values.
    """
    if args.list:
        width = max(map(len, SCENARIOS))
        for name, sc in SCENARIOS.items():
            sessions = f"{sc.sessions} x " if sc.sessions > 1 else ""
            defaults = f"{sessions}{sc.duration:g} s at {sc.rate:g} Hz"
            print(f"{name:<{width}}  {defaults:<22}  {sc.description}")
        return 0
    if not args.scenario or not args.out:
        raise InputError("give a SCENARIO and --out FILE.csv (or --list)")
    records = make_sessions(
        args.scenario,
        duration=args.duration,
        rate=args.rate,
        seed=args.seed,
        **_overrides(args.set),
    )
    try:
        if len(records) == 1:
            written = [write_record(records[0], args.out, time=not args.no_time)]
        else:
            written = write_sessions(records, args.out, time=not args.no_time)
    except OSError as exc:
        raise InputError(f"cannot write {args.out}: {exc}") from exc
    for record, (csv_path, truth_path) in zip(records, written):
        print(f"wrote {csv_path} ({record.n_samples} samples) and {truth_path}")
    return 0


def _overrides(pairs: Sequence[str]) -> dict[str, object]:
    out: dict[str, object] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise InputError(f"--set expects KEY=VALUE, got {pair!r}")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
    return out

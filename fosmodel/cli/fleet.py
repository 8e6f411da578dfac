"""The ``fleet`` command: the six-axis workflow on every record of a batch, resumable.

Each record (one IMU) is a task, run in this process or on a Dask cluster, whose results go
to a folder of its own in the store as it ends; a rerun skips the records already there
(:mod:`fosmodel.workflows.fleet`).
"""

from __future__ import annotations

import argparse
import sys

from .arguments import RECORD_HELP, name_list, positive_float, positive_int
from .imu import add_workflow_options, workflow_settings

#: The steps of :data:`fosmodel.workflows.imu.STEPS`, spelt here: importing the workflow
#: would pull in every step's modules whenever the parser is built.
STEPS = ("allan", "study", "loop")


def configure_parser(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Add the ``fleet`` command's arguments to ``parser`` and return it."""
    parser.add_argument("files", nargs="+", metavar="FILE",
                        help=RECORD_HELP.replace("record:", "records, one IMU each:"))
    add_workflow_options(parser)
    parser.add_argument("--steps", type=name_list, default=",".join(STEPS),
                        help="what each record goes through, among " + ",".join(STEPS))
    parser.add_argument("--reports", action="store_true",
                        help="also write each record's reports (tables, figures) in the store")
    parser.add_argument("--out", required=True,
                        help="the results store (created): a folder per record, published "
                             "when it is done, and the summary fleet.md/csv/tex; a rerun "
                             "skips the records done")
    dask = parser.add_mutually_exclusive_group()
    dask.add_argument("--scheduler", metavar="ADDRESS",
                      help="run the records on the Dask cluster of this scheduler (e.g. "
                           "tcp://10.0.0.5:8786); its workers must see the files and --out")
    dask.add_argument("--workers", type=positive_int, metavar="N",
                      help="run the records on a local Dask cluster of N single-threaded "
                           "processes (default: one after the other in this process)")
    parser.add_argument("--connect-timeout", type=positive_float, default="10", metavar="S",
                        help="seconds to wait for --scheduler")
    return parser


def fleet(args: argparse.Namespace) -> int:
    """Run the fleet of ``args.files`` into the store ``args.out``; print what it did."""
    from ..io.loader import parse_scales
    from ..io.output import writable_directory
    from ..study.runner import dask_client
    from ..workflows.fleet import MARKER, FleetConfig, run_fleet
    from ..workflows.imu import ImuConfig
    from .commands import _check_dask

    _check_dask(args)
    out = writable_directory(args.out)
    load = dict(rate=args.rate, scale=parse_scales(args.scale or []), uniform=args.uniform,
                outliers=args.outliers, gaps=args.gaps, topic=args.topic,
                temperature_topic=args.temperature_topic)
    config = FleetConfig(imu=ImuConfig(**workflow_settings(args), n_jobs=1),
                         steps=tuple(args.steps), split=args.split, loop_split=args.loop_split,
                         columns=tuple(args.columns) if args.columns else None,
                         units=args.units, temperature=args.temperature, load=load,
                         reports=args.reports, static_only=args.static_only)
    try:
        with dask_client(args.scheduler, args.workers, args.connect_timeout) as client:
            result = run_fleet(args.files, out, config, client=client,
                               progress=sys.stderr.isatty())
    except KeyboardInterrupt:
        # each record is published whole as it ends: say which are on disk, as a rerun skips them
        done = sorted(m.parent.name for m in out.glob(f"*/{MARKER}")) if out.is_dir() else []
        print(f"fosmodel: interrupted; {len(done)} of {len(args.files)} records finished and "
              f"kept in {out.resolve()}/" + (f" ({', '.join(done)})" if done else "")
              + (": a rerun skips them" if done else ""), file=sys.stderr)
        return 130
    print(f"fleet of {len(result.seconds)} records: {len(result.ran)} run, "
          f"{len(result.skipped)} already in the store; {len(result.table)} rows (a record "
          f"and axis each) in {out.resolve()}/fleet.md, .csv and .tex")
    return 0

"""``cassi versions``: list the registered versions (built-in and from entry points)."""
from __future__ import annotations

import argparse

from cassi.versions.registry import available_versions, get_version


def _run(args: argparse.Namespace) -> int:
    names = available_versions()
    if args.check:
        for name in names:      # importing each one proves its lazy target resolves
            get_version(name)
    for name in names:
        print(name)
    return 0


def register(sub) -> None:
    """Add the ``versions`` subcommand to the ``cassi`` subparsers."""
    parser = sub.add_parser("versions", help="list the registered CASSI versions, one a line",
                            description="List the registered versions: parke-1974, cassi-1.0, "
                                        "cassi-2.0, cassi-2.1 and any from the 'cassi.versions' "
                                        "entry point group.")
    parser.add_argument("--check", action="store_true",
                        help="load every version first (fails on one that cannot be imported)")
    parser.set_defaults(func=_run)

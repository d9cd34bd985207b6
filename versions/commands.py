"""``cassi versions``: list the registered versions (built-in and from entry points)."""
from __future__ import annotations

import argparse

from cassi.versions.registry import BUILT_IN_VERSIONS, available_versions, get_version


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
                            description=f"List the registered versions: "
                                        f"{', '.join(BUILT_IN_VERSIONS)} and any from the "
                                        f"'cassi.versions' entry point group.")
    parser.add_argument("--check", action="store_true",
                        help="load every version first (fails on one that cannot be imported)")
    parser.set_defaults(func=_run)

"""The ``cassi`` command line.

Each cassi package contributes its subcommands through the ``cassi.commands`` entry point
group (``module:register``, called with the argparse subparsers object), so this module never
imports a layer it must not depend on. A subcommand names its handler as a
``"module:function"`` string (:func:`cassi.common.lazy.resolve`), imported only when it runs. Exit codes: 0 success, 2 bad input, 1 other failure.
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from importlib.metadata import entry_points, version

from cassi.common.errors import CassiInputError
from cassi.common.lazy import resolve

EXIT_OK, EXIT_FAILURE, EXIT_BAD_INPUT = 0, 1, 2
EXIT_TERMINATED = 128 + signal.SIGTERM


class Terminated(Exception):
    """SIGTERM, raised in the main thread so that every ``with`` block unwinds (a run's
    executor stops its workers) instead of the process vanishing with its workers running."""


def _on_sigterm(signum, frame):
    raise Terminated()


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # argparse's own bad-input path: exit 2 like ours
        self.print_usage(sys.stderr)
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="cassi", description="cassi-farm: the evaluation harness and batch render "
                     "farm for CASSI, the Computer Animated Speech SImulator. Without --corpus, "
                     "commands use the embedded synthetic corpus. See README.md.")
    parser.add_argument("--version", action="version", version=f"cassi-farm {version('cassi-farm')}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for ep in sorted(entry_points(group="cassi.commands"), key=lambda e: e.name):
        ep.load()(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(levelname)s %(name)s: %(message)s")
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if main_thread else None
    try:
        return int(resolve(args.func)(args) or EXIT_OK)
    except Terminated:
        return _terminated()
    except CassiInputError as err:
        print(f"cassi: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print("cassi: interrupted", file=sys.stderr)
        return EXIT_FAILURE
    except Exception as err:  # noqa: BLE001 - the CLI boundary: report, never a traceback dump
        if isinstance(err.__cause__, Terminated):  # raised inside native code (Ray's wait),
            return _terminated()                   # which wraps it in a SystemError
        logging.getLogger("cassi").debug("failure", exc_info=True)
        print(f"cassi: failed: {type(err).__name__}: {err}", file=sys.stderr)
        return EXIT_FAILURE
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)


def _terminated() -> int:
    print("cassi: terminated (SIGTERM); finished jobs are kept, rerun the same command "
          "to resume", file=sys.stderr)
    return EXIT_TERMINATED


if __name__ == "__main__":
    sys.exit(main())

"""The ``centrality-vision`` command.

One module per subcommand, each holding its arguments beside its handler
(``add_parser(sub)`` and ``run(args) -> int``): :mod:`.graph`, :mod:`.centrality`,
:mod:`.register`, :mod:`.match`, :mod:`.classify`, :mod:`.demo` and :mod:`.reproduce`
(which reads the one registry of experiments, :mod:`centrality_vision.experiments`).
Files are read by :mod:`centrality_vision.io` and written by one output writer
(:mod:`._output`), always with the run's parameters. Heavy imports happen inside each
handler; progress bars, notes and warnings go to stderr, one line each, and bars only
when stderr is a terminal unless ``--progress``/``--no-progress`` says otherwise. The
command line, not the library, chooses matplotlib's Agg backend.

``main(argv) -> int`` returns the exit status: 0 success; 2 a usage error, a bad input
(:class:`~centrality_vision.exceptions.InputError`), a file that cannot be read or
written (``OSError``) or a package edited during a run
(:class:`~centrality_vision.exceptions.CodeChangedError`), each told in one line; 130
interrupted; 1 a bug, shown with its traceback.
"""

from __future__ import annotations

import argparse
import re
import sys

from . import centrality, classify, demo, graph, match, register, reproduce
from ._common import (
    CENTRALITY_NAMES,
    GPD_GRAPHS,
    GRAPH_KINDS,
    Parser,
    check_output_places,
    progress_on,
    quiet_progress,
)

__all__ = ["main", "build_parser", "CENTRALITY_NAMES", "GPD_GRAPHS", "GRAPH_KINDS"]

#: The subcommands, in the order of ``--help``.
COMMANDS = (demo, reproduce, graph, centrality, register, match, classify)


def build_parser() -> Parser:
    """The argument parser of ``centrality-vision`` with every subcommand.

    Examples
    --------
    >>> parser = build_parser()
    >>> args = parser.parse_args(["centrality", "points.csv", "--out", "out.csv"])
    >>> parser.prog, args.command, args.centrality, args.graph, args.out
    ('centrality-vision', 'centrality', 'closeness', 'delaunay', 'out.csv')
    """
    from .. import __version__

    parser = Parser(
        prog="centrality-vision", description="Graph centrality for computer vision (de Sousa, TU Wien, 2015)."
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (0 success, 2 bad input, 1 a bug, 130 interrupted).

    Usage errors exit through :class:`SystemExit` (status 2), as argparse does. Bad inputs
    (:class:`~centrality_vision.exceptions.InputError`), files that cannot be read or
    written (``OSError``) and a package edited during a run
    (:class:`~centrality_vision.exceptions.CodeChangedError`) are printed as one line on
    stderr and give status 2. Any other
    exception is a bug: its traceback is printed and the status is 1. Warnings are
    printed as one line each and recorded in the outputs that keep them.

    Examples
    --------
    The degree of the five points of a square and its centre (notes go to stderr):

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     points, out = Path(folder) / "square.csv", Path(folder) / "degree.csv"
    ...     np.savetxt(points, [[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0.5]], delimiter=",", header="x,y", comments="")
    ...     status = main(["centrality", str(points), "--centrality", "degree", "--out", str(out)])
    ...     table = out.read_text().splitlines()
    ...     missing = main(["centrality", str(Path(folder) / "none.csv"), "--out", str(out)])
    >>> status, table[0], table[-1]
    (0, 'node,x,y,degree', '4,0.5,0.5,4.0')
    >>> missing  # a file that cannot be read: one line on stderr, status 2
    2
    """
    import traceback
    import warnings

    from ..exceptions import CodeChangedError, InputError

    parser = build_parser()
    args, extras = parser.parse_known_args(_glued_columns(sys.argv[1:] if argv is None else list(argv)))
    if extras:  # argparse would blame the top-level parser; name the subcommand instead
        getattr(args, "_parser", parser).error(f"unrecognized arguments: {' '.join(extras)}")
    if args.command is None:  # a usage error, as in argparse: the help on stderr, status 2
        parser.print_help(sys.stderr)
        return 2
    prog = f"centrality-vision {args.command}"
    args._warnings = []

    def show(message, category, filename, lineno, file=None, line=None):
        text = _in_cli_words(" ".join(str(message).split()), getattr(args, "_parser", None), args)
        args._warnings.append(f"{category.__name__}: {text}")
        print(f"{prog}: warning: {text}", file=sys.stderr)

    try:
        check_output_places(args)
        with warnings.catch_warnings(), quiet_progress(progress_on(args)):
            warnings.filterwarnings("always", category=UserWarning)  # shown on one line, never raised
            warnings.showwarning = show
            return args.run(args)
    except (InputError, OSError, CodeChangedError) as exc:
        message = _in_cli_words(" ".join(str(exc).split()) or type(exc).__name__, getattr(args, "_parser", None), args)
        print(f"{prog}: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        if _caused_by_interrupt(exc):  # a compiled kernel turns Ctrl-C into a SystemError
            print(f"{prog}: interrupted", file=sys.stderr)
            return 130
        traceback.print_exc()
        print(
            f"{prog}: internal error (a bug in centrality-vision; please report it with the traceback above)",
            file=sys.stderr,
        )
        return 1


def _caused_by_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in the chain of causes of ``exc``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _glued_columns(argv: list[str]) -> list[str]:
    """``--columns -1,0`` as ``--columns=-1,0``: argparse reads a value that starts with '-'
    and is not one number as an option ("expected one argument")."""
    out = []
    for token in argv:
        if out and out[-1] == "--columns" and re.fullmatch(r"-\d[\d,\s-]*", token):
            out[-1] = f"--columns={token}"
        else:
            out.append(token)
    return out


def _in_cli_words(message: str, parser, args: argparse.Namespace | None = None) -> str:
    """A library message in this command's words.

    - A parameter (```tol```, or an estimator's ```RigidCPD.tol```) becomes its option
      (``--tol``), and a setting (```tol=1e-05```) the option with its value
      (``--tol 1e-05``); a command's
      ``_cli_phrases`` (``{library phrase: command-line phrase}``) come first, for
      settings the command spells otherwise (``match``: ```scale=True``` is
      ``--transform similarity``).
    - An input file's parameter (```moving```) becomes its argument and the file given
      (``MOVING (scan.ply)``); so do the library names in a command's ``_cli_aliases``
      (``{library name: argument}``: ```points``` and ```image``` are ``centrality``'s
      INPUT).
    - A sentence that starts "From Python, " is advice only a Python caller can follow
      (``moving_graph``, say), and is left out.
    """
    if parser is None:
        return message
    for phrase, replacement in getattr(args, "_cli_phrases", {}).items():
        message = message.replace(phrase, replacement)
    aliases = getattr(args, "_cli_aliases", {})
    for action in parser._actions:
        longs = [option for option in action.option_strings if option.startswith("--")]
        if longs:

            def setting(match, option=longs[0], flag=action.nargs == 0):
                value = match.group(1).strip("'\"")
                return option if flag and value == "True" else f"{option} {value}"

            message = re.sub(rf"`{re.escape(action.dest)}=([^`]*)`", setting, message)
            # an estimator's parameter (`RigidCPD.tol`) is the option too
            message = re.sub(rf"`(?:[A-Z]\w*\.)?{re.escape(action.dest)}`", longs[0], message)
        elif not action.option_strings and isinstance(getattr(args, action.dest, None), str):
            metavar = action.metavar or action.dest.upper()
            for name in (action.dest, *(name for name, dest in aliases.items() if dest == action.dest)):
                message = message.replace(f"`{name}`", f"{metavar} ({getattr(args, action.dest)})")
    sentences = re.split(r"(?<=[.!?])\s+(?=[A-Z(])", message)
    return " ".join(sentence for sentence in sentences if not sentence.startswith("From Python, "))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

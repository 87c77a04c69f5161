"""`jointbench`: the command line of docs/cli.md, one module per command.

Exit status: 0 success, 2 bad input (one message on stderr naming the file, line or column),
1 anything else. With --json a command prints exactly one JSON object on stdout.

The dispatcher imports a command's module only when that command runs (`parser`), so that
`jointbench --help` loads neither numpy nor MuJoCo.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys

from jointbench.bench.cli.common import (EXIT_BAD_INPUT, EXIT_FAILURE, Terminated,
                                         is_simulation_error, one_line, trap_signals)
from jointbench.bench.cli.parser import build_parser, command_module

__all__ = ["main", "build_parser"]


def main(argv: list[str] | None = None) -> int:
    """Run `jointbench` with `argv` (default sys.argv[1:]); returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not args.command:
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    command = command_module(args.command)
    # No command renders with MuJoCo: skip its OpenGL probe at import (glfw, about 0.05 s of
    # every start-up). A user's own MUJOCO_GL setting wins.
    os.environ.setdefault("MUJOCO_GL", "disable")
    # The command's library first: an interrupt inside an extension's import (numpy's, say)
    # would surface as an ImportError, not as the interruption it is.
    for name in getattr(command, "library", lambda _: command.LIBRARY)(args):
        importlib.import_module(name)
    restore_signals = trap_signals()
    try:
        return command.run(args)
    except ValueError as err:
        # bad input: UsageError and the library's LogError, ModelStructureError,
        # NotIdentifiable, InversionError, all ValueErrors
        print(f"jointbench {args.command}: error: {one_line(err)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"jointbench {args.command}: interrupted", file=sys.stderr)
        return 130
    except Terminated as sig:
        print(f"jointbench {args.command}: terminated by {signal.Signals(sig.signum).name}",
              file=sys.stderr)
        return 128 + sig.signum
    except BrokenPipeError:
        # The reader of stdout went away (`| head`): nothing more to say, and no complaint
        # from the interpreter when it flushes stdout at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + 13
    except Exception as err:  # the contract: never a traceback
        if is_simulation_error(err):
            print(f"jointbench {args.command}: error: {one_line(err)}", file=sys.stderr)
            return EXIT_BAD_INPUT
        print(f"jointbench {args.command}: internal error: {type(err).__name__}: {err}",
              file=sys.stderr)
        return EXIT_FAILURE
    finally:
        restore_signals()


if __name__ == "__main__":
    sys.exit(main())

"""``python -m vo_lib COMMAND``: the command line, in :mod:`vo_lib.cli`."""

import os
import signal
import sys


def _while_loading(signum, frame) -> None:
    """A signal before the command line has loaded: nothing has begun, so one line, not a traceback."""
    os.write(
        2, f"python -m vo_lib: {signal.Signals(signum).name} while starting; nothing was done\n".encode()
    )
    os._exit(128 + signum)


if __name__ == "__main__":
    for kind in (signal.SIGINT, signal.SIGTERM):
        signal.signal(kind, _while_loading)
    from vo_lib.cli.main import entry  # which keeps a handler of its own until the command begins

    sys.exit(entry())

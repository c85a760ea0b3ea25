"""``python -m vo_lib COMMAND``: the command line, in :mod:`vo_lib.cli`."""

import sys

from vo_lib.cli.main import entry

if __name__ == "__main__":
    sys.exit(entry())

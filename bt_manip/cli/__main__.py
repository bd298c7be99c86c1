"""``python -m bt_manip.cli``: the ``bt-manip`` command line."""

import sys

from bt_manip.cli import main

if __name__ == "__main__":  # not when a spawned worker process imports it
    sys.exit(main())

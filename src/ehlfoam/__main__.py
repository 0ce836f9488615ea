"""``python -m ehlfoam ...``: the ``ehlfoam`` command."""

import sys

from ehlfoam.cli.main import main

if __name__ == "__main__":
    sys.exit(main())

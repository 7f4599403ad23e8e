"""``python -m app.sweep ...``: the same as ``pelvic-walk sweep ...``."""

import sys

from app.sweep.cli import main

if __name__ == "__main__":
    sys.exit(main())

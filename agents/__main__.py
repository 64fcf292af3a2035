"""``python -m agents ...`` (from a checkout) and the ``srenv-agents`` command (from the wheel)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())

"""``python -m impactlib ...``: see :mod:`impactlib.cli`."""
import sys

from .cli import main

sys.exit(main())

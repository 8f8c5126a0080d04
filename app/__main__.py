"""``python -m impact_explorer serve ...``: see :mod:`impact_explorer.serve`."""
import sys

from .serve import main

sys.exit(main())

"""python -m rsm_tools.bench: what ./tools/bench runs (see the package's docstring)."""
import sys

from . import main

sys.exit(main())

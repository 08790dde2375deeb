"""``python -m a1_leg_fk.cli``: the ``a1-leg-fk`` command without its console script."""

import sys

from a1_leg_fk.cli import main

sys.exit(main())

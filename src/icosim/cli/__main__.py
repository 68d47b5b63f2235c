"""``python -m icosim.cli``: the ``icosim`` command."""

import sys

from . import main

sys.exit(main())

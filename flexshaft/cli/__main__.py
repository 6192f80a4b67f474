"""``python -m flexshaft.cli ...``: the same as the ``flexshaft`` command."""

import sys

from flexshaft.cli import main

sys.exit(main())

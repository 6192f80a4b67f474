"""``python -m flexshaft ...``: the same as the ``flexshaft`` command."""

import sys

from flexshaft.cli import main

sys.exit(main())

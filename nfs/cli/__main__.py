"""``python -m nfs.cli``: the ``nfs`` command."""

import sys

from . import main

sys.exit(main())

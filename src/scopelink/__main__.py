"""``python -m scopelink`` runs the command line, as the ``scopelink`` program does."""

import sys

from scopelink.cli import entry

sys.exit(entry())

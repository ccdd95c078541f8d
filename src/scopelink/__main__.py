"""``python -m scopelink`` runs the command line."""

import sys

from scopelink.cli.main import main

sys.exit(main())

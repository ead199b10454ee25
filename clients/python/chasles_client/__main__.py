"""``python3 -m chasles_client``: the command-line entry (see chasles_client.cli)."""

import sys

from .cli import main

sys.exit(main())

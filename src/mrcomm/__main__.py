"""``python -m mrcomm``: the ``mrcomm`` command."""

import sys

from mrcomm.cli.main import app

sys.argv[0] = "mrcomm"  # what usage lines and messages call the command
app()

"""``python -m offline_prog`` is the ``offline-prog`` command."""

import sys

from offline_prog.cli import command

sys.exit(command())

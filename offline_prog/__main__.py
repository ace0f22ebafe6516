"""``python -m offline_prog`` is the ``offline-prog`` command."""

import gc
import sys

# No collection while the command imports (cli.main freezes what the imports made out
# of the collector and enables it again): each one walked the growing heap of pydrake
# and scipy objects, 40-60 ms of the seal demo.
gc.disable()

from offline_prog.cli import command  # noqa: E402

sys.exit(command())

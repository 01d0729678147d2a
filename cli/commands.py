"""Registration of the sub-commands (each lives in its own module of ``acid_cli``).

Add one block per command module, in pipeline order.
"""

from __future__ import annotations

from acid_cli.main import app  # noqa: F401  (command modules register on it below)

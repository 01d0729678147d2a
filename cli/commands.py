"""Registration of the sub-commands (each lives in its own module of ``acid_cli``).

Add one block per command module, in pipeline order.
"""

from __future__ import annotations

from acid_cli.main import app  # noqa: F401  (command modules register on it below)

# isort: split
from acid_cli import excite  # noqa: E402

app.command(name="excite")(excite.excite)

from acid_cli import import_data  # noqa: E402

app.command(name="import")(import_data.import_data)

from acid_cli import validate  # noqa: E402

app.command(name="validate")(validate.validate)

from acid_cli import speed_sweep  # noqa: E402

app.command(name="speed-sweep")(speed_sweep.speed_sweep)

from acid_cli import fit  # noqa: E402

app.command(name="fit")(fit.fit)

from acid_cli import mpc_check  # noqa: E402

app.command(name="mpc-check")(mpc_check.mpc_check)

from acid_cli import reproduce  # noqa: E402

app.command(name="reproduce")(reproduce.reproduce)

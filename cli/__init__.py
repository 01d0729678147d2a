"""acid's command-line interface: a thin Typer layer over the ``acid`` library."""

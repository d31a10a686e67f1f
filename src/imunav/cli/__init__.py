"""The ``imunav`` command line (typer): one module per command group."""

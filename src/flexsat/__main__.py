"""``python -m flexsat``: the ``flexsat`` command line."""

from flexsat.cli import app

app(prog_name="flexsat")

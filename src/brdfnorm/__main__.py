"""``python -m brdfnorm``: the command line, as the ``brdfnorm`` script runs it."""

from .cli import main

main()

"""``python -m armguard.cli``: the same as the ``armguard`` command."""

from . import main

main()

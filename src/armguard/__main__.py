"""``python -m armguard``: the same as the ``armguard`` command (and ``python -m armguard.cli``)."""

from armguard.cli import main

if __name__ == "__main__":
    main()

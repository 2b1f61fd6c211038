"""``python -m meshcol``: the same as the ``meshcol`` command."""

from meshcol.cli import main

if __name__ == "__main__":
    main(prog_name="meshcol")

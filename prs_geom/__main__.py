"""``python -m prs_geom``: the command line :func:`prs_geom.cli.entry_point`."""
from prs_geom.cli import entry_point

__all__: list[str] = []

if __name__ == "__main__":  # pragma: no cover
    entry_point()

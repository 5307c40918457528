"""`python -m swarmgen`."""

from swarmgen.cli import run

if __name__ == "__main__":
    run()

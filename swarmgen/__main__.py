"""`python -m swarmgen`."""

from swarmgen.cli import main

if __name__ == "__main__":
    main()

"""``python3 -m closed_loop.sweep SPEC.yaml``: the sweep command (``closed_loop.batch.sweep``)."""
import sys

from closed_loop.batch.sweep import main

if __name__ == '__main__':
    sys.exit(main())

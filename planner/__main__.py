import os
import sys

try:
    from planner.cli import main
except KeyboardInterrupt:  # Ctrl-C while the modules load: the same one line as later
    print("planner: interrupted", file=sys.stderr, flush=True)
    os._exit(130)

sys.exit(main())

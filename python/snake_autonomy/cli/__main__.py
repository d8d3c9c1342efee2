"""`python3 -m snake_autonomy.cli COMMAND ...`: the same as the `snake_autonomy` script."""
import sys

from snake_autonomy.cli import main

sys.exit(main())

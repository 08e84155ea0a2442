"""`python -m mrclutch`: the command line (mrclutch.cli.main), as the `mrclutch` script."""

import sys

from mrclutch.cli.main import main

sys.exit(main())

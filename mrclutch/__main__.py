import sys

from mrclutch.cli import main

sys.exit(main())

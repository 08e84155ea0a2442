import sys

from mrclutch.cli.main import main

sys.exit(main())

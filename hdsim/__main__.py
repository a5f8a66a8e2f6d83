import sys

from hdsim.cli import main

sys.exit(main())

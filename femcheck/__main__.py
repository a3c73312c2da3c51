import sys

from femcheck.cli import main

sys.exit(main())

"""`python -m testbenches.embedded`: see testbenches.embedded.build."""

import sys

from .cli import main

sys.exit(main())

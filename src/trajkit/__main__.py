"""``python -m trajkit``: the ``trajkit`` command."""

import sys

from .cli import main

sys.exit(main())

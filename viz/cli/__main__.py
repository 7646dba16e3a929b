"""``python -m mechviz.viz.cli``: the ``mechviz`` command."""

import sys

from . import main

sys.exit(main())

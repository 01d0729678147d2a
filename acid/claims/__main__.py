"""``python -m acid.claims [summary.json]``."""

import sys

from acid.claims.headline import main

sys.exit(main())

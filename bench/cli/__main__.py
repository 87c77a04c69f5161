"""`python -m jointbench.bench.cli`: the same as the `jointbench` command."""

import sys

from jointbench.bench.cli import main

sys.exit(main())

"""``python -m omnibot``: the omnibot command line."""

from omnibot.cli import main

raise SystemExit(main())

"""``python -m hexapod_model``: the ``hexapod`` command."""

from .cli import main

raise SystemExit(main())

"""``python -m hexapod_model.cli``: the ``hexapod`` command."""

from . import main

raise SystemExit(main())

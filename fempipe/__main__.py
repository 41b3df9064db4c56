from fempipe.cli import main

raise SystemExit(main())

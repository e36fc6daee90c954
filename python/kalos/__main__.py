"""``python -m kalos render --dask ADDRESS SCENE [options]``: a render on a Dask cluster,
with ``kalos render``'s options and outputs (``kalos render --dask`` runs this). Other
commands are the ``kalos`` binary's."""

import sys

from .distributed import main

if __name__ == "__main__":
    args = sys.argv[1:]
    if not args or args[0] != "render" or not any(a == "--dask" or a.startswith("--dask=") for a in args):
        print("kalos: error: python -m kalos runs `render --dask ADDRESS SCENE [options]` only; "
              "the other commands are the kalos binary's", file=sys.stderr)
        raise SystemExit(2)
    raise SystemExit(main(args[1:]))

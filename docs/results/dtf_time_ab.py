#!/usr/bin/env python3
"""Wall-clock time of `--method dtf` against the plain render, run side by side.

Usage: dtf_time_ab.py PAIRS KALOS SCENE [RENDER OPTIONS...]
  e.g. dtf_time_ab.py 3 target/release/kalos cornell            # the defaults
       dtf_time_ab.py 3 target/release/kalos room --res 200x200 --spp 256

The same as `time_ab.py PAIRS KALOS SCENE [RENDER OPTIONS...] -- --method dtf`."""
import os, runpy, sys

sys.argv = [sys.argv[0], *sys.argv[1:], "--", "--method", "dtf"]
runpy.run_path(os.path.join(os.path.dirname(os.path.abspath(__file__)), "time_ab.py"), run_name="__main__")

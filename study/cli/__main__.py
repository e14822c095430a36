"""``python -m flipstudy.study.cli``"""
import sys

from . import main

sys.exit(main())

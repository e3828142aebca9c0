"""Tests run in fast mode so nothing they write lands in data/results or figures."""

import os

os.environ["MAVAC_FAST"] = "1"

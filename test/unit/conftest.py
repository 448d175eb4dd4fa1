"""Unit tests import closed_loop from the source tree; no ROS master is needed or started."""
import os
import sys

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
if SRC not in sys.path:
    sys.path.insert(0, SRC)

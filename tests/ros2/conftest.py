"""Each ROS 2 test process talks ROS 2 on a domain of its own, on this host only (set
before any rclpy context exists: every context and child process reads them)."""

from __future__ import annotations

import os

os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

"""ROS 2 adapters (optional extra ``mrcomm[ros2]``; nothing in the core imports rclpy).

* :mod:`mrcomm.ros2.runtime` — checking that rclpy and ``nav2_msgs`` are importable,
  the names and QoS of a robot's Nav2 interfaces, and the thread an rclpy executor
  spins in (every ROS call happens there; other threads hand it work).
* :mod:`mrcomm.ros2.nav2_base` — :class:`Nav2Base`, the Base port on a Nav2 robot:
  ``NavigateToPose`` goals, the pose from ``amcl_pose``, distance and speed from ``odom``.
* :mod:`mrcomm.ros2.nav2_server` — the other side, for the live world process
  (``mrcomm world --ros2``): every simulated robot as a Nav2-compatible action server
  with its ``amcl_pose`` and ``odom`` publishers.
"""

"""ROS 2 support: generated interface packages (messages and actions) and their build with the
ROS 2 wheels from PyPI (the optional `ros` extra, `make ros`). See docs/ros2.md."""

"""A hand-written ROS 2 platform (not generated) for the declared-interface tests."""

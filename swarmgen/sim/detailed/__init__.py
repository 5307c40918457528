"""The detailed level of `swarmgen simulate`: the generated rclpy swarm, unmodified, against the
behaviour library and the continuous world on ROS 2 (docs/detailed.md)."""

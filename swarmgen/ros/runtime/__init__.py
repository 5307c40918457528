"""What generated rclpy code imports: a swarm member as a ROS 2 node (the statechart engine's
host), scripted action servers that simulate the behaviour library, the swarm launcher and the
replay harness. Needs rclpy (the `ros` extra); never imports the compiler. The rclpy backend
copies this package into its output (`<swarm>_nodes/_ros/`), next to `swarmgen.runtime`."""

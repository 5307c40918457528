"""Traces of swarm runs as ROS 2 bags (`bag.py` the format, `recorder.py` writing, `reader.py`
reading), and the paper's event timeline over many runs (`timeline.py`). See docs/trace.md.

rosbags (and numpy, matplotlib for the timeline) come with the `ros` or `trace` extra; they are
imported only when a trace is written or read, never by the compiler.
"""

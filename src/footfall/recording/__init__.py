"""Recordings: MCAP and ROS bags written and replayed, rerun logs."""

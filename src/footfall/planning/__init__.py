"""Planning: footholds on the score map, the floor height, swing clearance."""

"""Scoring: how walkable each cell of a height map is."""

"""Sensing: camera models, poses and pose-estimate noise."""

"""Mapping: the rolling height map built from depth images and poses."""

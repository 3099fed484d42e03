"""Recorded data: RGB-D sequences with poses (TUM layout) and converters into it."""

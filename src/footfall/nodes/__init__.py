"""Nodes: the parts of footfall that run on their own and talk only through messages."""

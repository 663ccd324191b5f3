"""A 2-D navigation-and-manipulation domain in PDDLStream's idiom (see samplers.py)."""

"""Compatibility layers for users coming from other planning frameworks."""

"""SDAR: dependency-driven dual-arm task search (SDAR-T) and best-first grounding (SDAR-M)."""

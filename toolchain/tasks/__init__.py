"""invoke task modules, one per area (see tasks.py)."""

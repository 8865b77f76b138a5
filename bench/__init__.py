"""Benchmarks: each module defines TITLE and run(quick: bool) -> Markdown (see toolchain/tasks/core.py)."""

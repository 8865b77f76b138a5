"""AT89S51 acquisition firmware: C sources (``*.c``, ``sim/``) and the Python
tooling that builds them with SDCC and runs them in the s51 simulator
(:mod:`firmware.tool`). See docs/firmware.md."""

"""Build support shared by tasks.py and the tests: target definitions and compilers."""

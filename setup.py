"""Build glue: setuptools needs `cffi_modules` passed here (see pyproject.toml for metadata)."""
from setuptools import setup

setup(
    cffi_modules=[
        "attitude_c/_build/ffibuild.py:ffi_f64",
        "attitude_c/_build/ffibuild.py:ffi_f32",
    ],
)

"""Build glue: setuptools needs `cffi_modules` and the version (read from
csrc/include/attitude/version.h) passed here (see pyproject.toml for metadata).

The CFFI extensions are compiled for CPython's stable ABI (cffi defines
Py_LIMITED_API: files `_att_f64.abi3.so`), so one wheel serves every
CPython >= 3.9: the wheel is tagged `cp39-abi3`. Not on a debug or
free-threaded interpreter, where cffi itself turns the limited API off.
"""

import importlib.util
import sys
import sysconfig
from pathlib import Path

from setuptools import setup

# The version's one source is csrc/include/attitude/version.h (pyproject.toml
# declares it dynamic); loaded by path: importing attitude_c needs numpy.
_spec = importlib.util.spec_from_file_location(
    "_att_version", Path(__file__).resolve().parent / "attitude_c" / "_build" / "version.py")
_version = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_version)

LIMITED_API = not hasattr(sys, "gettotalrefcount") and not sysconfig.get_config_var("Py_GIL_DISABLED")

setup(
    version=_version.version(),
    cffi_modules=[
        "attitude_c/_build/ffibuild.py:ffi_f64",
        "attitude_c/_build/ffibuild.py:ffi_f32",
    ],
    options={"bdist_wheel": {"py_limited_api": "cp39"}} if LIMITED_API else {},
)

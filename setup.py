"""Build glue: setuptools needs `cffi_modules` passed here (see pyproject.toml for metadata).

The CFFI extensions are compiled for CPython's stable ABI (cffi defines
Py_LIMITED_API: files `_att_f64.abi3.so`), so one wheel serves every
CPython >= 3.9: the wheel is tagged `cp39-abi3`. Not on a debug or
free-threaded interpreter, where cffi itself turns the limited API off.
"""

import sys
import sysconfig

from setuptools import setup

LIMITED_API = not hasattr(sys, "gettotalrefcount") and not sysconfig.get_config_var("Py_GIL_DISABLED")

setup(
    cffi_modules=[
        "attitude_c/_build/ffibuild.py:ffi_f64",
        "attitude_c/_build/ffibuild.py:ffi_f32",
    ],
    options={"bdist_wheel": {"py_limited_api": "cp39"}} if LIMITED_API else {},
)

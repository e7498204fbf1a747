"""Authenticating LCM messages for qrtpland (docs/security.md), with PyNaCl:
Signer, SignedPublisher, KeyFileError, scan_sensor_id, gen_keys.

The code's one home is the Python package, python/qrtplan/auth.py
(qrtplan.auth when installed); this file loads it from the source tree for
the tools, tests and examples that put lcm-gen's build/lcmtypes/python
first on sys.path (where `qrtplan` is the generated message package).
"""
import importlib.util
import os

_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                     "python", "qrtplan", "auth.py")
_spec = importlib.util.spec_from_file_location("_qrtplan_auth", _PATH)
_auth = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_auth)
globals().update({k: v for k, v in vars(_auth).items() if not k.startswith("__")})

"""The package's exceptions: each carries the C core's error code and text."""
from __future__ import annotations

__all__ = ["QrtError", "InvalidInput", "LimitsError", "TooBigError", "AbiError",
           "error_for"]


class QrtError(Exception):
    """An error of the C core (enum qrt_err); ``code`` is its value."""

    code = 0

    def __init__(self, message: str, code: int | None = None):
        super().__init__(message)
        if code is not None:
            self.code = code


class InvalidInput(QrtError, ValueError):
    """QRT_E_INVALID: NaN/Inf, a bad size, arm, margin or grid."""
    code = -1


class LimitsError(QrtError, ValueError):
    """QRT_E_LIMITS: joints outside the arm's limits."""
    code = -2


class TooBigError(QrtError):
    """QRT_E_TOO_BIG: the lattice exceeds this build's tables."""
    code = -3


class AbiError(QrtError):
    """QRT_E_ABI: the library was built with other settings."""
    code = -4


_BY_CODE = {c.code: c for c in (InvalidInput, LimitsError, TooBigError, AbiError)}


def error_for(rc: int, context: str, extra: str = "") -> QrtError:
    """The exception for core error rc: "context: <the core's text>[: extra]"."""
    from ._core import err_text
    msg = f"{context}: {err_text(rc)}" + (f": {extra}" if extra else "")
    return _BY_CODE.get(rc, QrtError)(msg, rc)

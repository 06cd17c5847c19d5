"""Device selection and the argument checks shared by every kernel entry point.

Shapes and dtypes are checked once, here, at the Python boundary; the kernels trust them.
Nothing in this module touches Warp at import time (Warp initialises itself on first use,
or a command line's :func:`init_warp`).
"""

from __future__ import annotations

import os
import sys
import tempfile

import numpy as np
import warp as wp

__all__ = ["NO_DRIVER_WARNING", "init_warp", "resolve_device", "device_array"]

#: The start of what Warp's native library writes to stderr on a machine without NVIDIA's
#: driver: the CPU path needs none, so a command line leaves it out (:func:`init_warp`).
NO_DRIVER_WARNING = b"Warp CUDA warning: Could not find or load the NVIDIA CUDA driver"

# numpy dtype kinds accepted for each kind of argument ('f' float, 'i'/'u' integer, 'b' bool)
_ACCEPTED_KINDS = {"float": "fiu", "int": "iu", "bool": "b"}


def init_warp() -> None:
    """Initialise Warp for a command line: its log at errors only, and its native
    library's start-up lines on stderr passed on but for :data:`NO_DRIVER_WARNING` (a
    command's failure is then its own one line). Does nothing more once Warp is running."""
    wp.config.log_level = wp.LOG_ERROR
    wp.config.quiet = True
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as captured:
        os.dup2(captured.fileno(), 2)
        try:
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        captured.seek(0)
        kept = [line for line in captured.read().splitlines(keepends=True)
                if not line.startswith(NO_DRIVER_WARNING)]
    if kept:
        os.write(2, b"".join(kept))


def resolve_device(device: str | wp.Device) -> wp.Device:
    """The Warp device called ``device``: ``"cpu"``, ``"cuda"`` (the default GPU) or ``"cuda:N"``.

    Raises:
        ValueError: this machine has no such device (no NVIDIA GPU or driver, wrong index);
            the message is written for the user (a CLI prints it as its one-line error).
    """
    if isinstance(device, wp.Device):
        return device
    name = str(device)
    available = [d.alias for d in wp.get_devices()]
    if name not in available and not (name == "cuda" and wp.is_cuda_available()):
        raise ValueError(
            f"device {name!r} is not available here (Warp sees: {', '.join(available)}); "
            "use --device cpu, or run on a machine with an NVIDIA GPU and driver")
    return wp.get_device(name)


def _describe(shape: tuple[int | str, ...], dims: dict[str, int]) -> str:
    parts = [f"{d}={dims[d]}" if isinstance(d, str) and d in dims else str(d) for d in shape]
    return "(" + ", ".join(parts) + ("," if len(parts) == 1 else "") + ")"


def device_array(name: str, value, shape: tuple[int | str, ...], dims: dict[str, int],
                 kind: str, dtype, device: wp.Device) -> wp.array:
    """Check an argument's shape and dtype and return it as a Warp array on ``device``.

    Args:
        name: the argument's name, for the error message.
        value: a NumPy array (or anything ``np.asarray`` takes), or a Warp array that
            already has the Warp ``dtype`` and lives on ``device``.
        shape: the expected NumPy shape; ints are fixed sizes, strings name sizes that
            must agree between arguments (``"P"`` for the population size).
        dims: sizes bound so far, by name; unbound names are bound here (updated in place).
        kind: ``"float"``, ``"int"`` or ``"bool"``: the NumPy dtypes accepted (floats also
            take integers); the value is converted to ``dtype``.
        dtype: the Warp dtype of the result; a vector dtype (``wp.vec2``...) folds the last
            axis of ``shape``, which must equal its length.
        device: where the result lives.

    Raises:
        ValueError: wrong number of axes, a size that disagrees with ``shape`` or ``dims``,
            a dtype of the wrong kind, or a Warp array of another dtype or device.
    """
    if isinstance(value, wp.array):
        actual = tuple(value.shape) + tuple(getattr(value.dtype, "_shape_", ()))
        if value.dtype != dtype or value.device != device:
            raise ValueError(f"{name} must be a Warp array of dtype {wp.types.type_repr(dtype)} on "
                             f"{device}, got {wp.types.type_repr(value.dtype)} on {value.device}")
    else:
        value = np.asarray(value)
        actual = value.shape
        if value.dtype.kind not in _ACCEPTED_KINDS[kind]:
            article = "an" if kind == "int" else "a"
            raise ValueError(f"{name} must be {article} {kind} array of shape {_describe(shape, dims)}, "
                             f"got dtype {value.dtype}")
    if len(actual) != len(shape) or any(
            isinstance(want, int) and got != want for got, want in zip(actual, shape)):
        raise ValueError(f"{name} must have shape {_describe(shape, dims)}, got {actual}")
    for got, want in zip(actual, shape):
        if isinstance(want, str):
            if dims.setdefault(want, got) != got:
                raise ValueError(f"{name} must have shape {_describe(shape, dims)}, got {actual}")
    if isinstance(value, wp.array):
        return value
    np_dtype = wp.dtype_to_numpy(getattr(dtype, "_wp_scalar_type_", dtype))
    return wp.array(np.ascontiguousarray(value, dtype=np_dtype), dtype=dtype, device=device)

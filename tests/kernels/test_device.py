"""The command lines' Warp start-up (kernels/device.py, init_warp)."""

import os
import subprocess
import sys

import warp as wp

from bodyfit.kernels import device


def test_init_warp_drops_the_no_driver_warning_and_passes_the_rest(monkeypatch, capfd):
    """What Warp's native library writes to fd 2 while it starts reaches stderr but for
    the no-driver warning, a line at a time."""
    def native_init():
        os.write(2, device.NO_DRIVER_WARNING + b". GPU execution will not be available.\n")
        os.write(2, b"Warp CUDA warning: Unable to determine CUDA driver version\n")

    monkeypatch.setattr(wp, "init", native_init)
    device.init_warp()
    err = capfd.readouterr().err
    assert err == "Warp CUDA warning: Unable to determine CUDA driver version\n"
    assert wp.config.log_level == wp.LOG_ERROR and wp.config.quiet


def test_a_command_line_starts_warp_without_a_word():
    """A fresh process: Warp started as the command lines start it writes nothing to
    stderr (on a machine without NVIDIA's driver its native warning is dropped)."""
    started = subprocess.run(
        [sys.executable, "-c", "from bodyfit.kernels.device import init_warp; init_warp(); "
                               "import warp; print(warp.is_cpu_available())"],
        capture_output=True, text=True, timeout=120, check=True)
    assert started.stdout.strip() == "True" and started.stderr == ""

"""`calib capture`'s work: board photos (or videos) to camera.json and a coverage picture.

Shared by the ``calib capture`` command and ``fitter demo``, so that both calibrate the
same way and write the same file.
"""

from __future__ import annotations

import datetime
import json
from pathlib import Path

import cv2

from bodyfit.calib.boards import BoardDetector, BoardSpec
from bodyfit.calib.capture import Calibration, CaptureSettings, calibrate, collect_views
from bodyfit.calib.coverage import coverage_fraction, coverage_picture
from bodyfit.calib.images import write_image
from bodyfit.common.command_line import bodyfit_version
from bodyfit.common.files import check_writable_dir, file_sha256, write_atomic

__all__ = ["capture_camera"]


def capture_camera(inputs: list[str], spec: BoardSpec, settings: CaptureSettings, output: Path,
                   coverage_path: Path, argv: list[str]) -> tuple[Calibration, float]:
    """Find ``spec`` in every input, solve the camera, write camera.json at ``output`` (the
    calibration's record, the coverage and the provenance: ``argv``, the inputs and their
    SHA-256, versions, time) and the coverage picture at ``coverage_path``.

    Returns:
        (the calibration, the fraction of the frame's grid cells holding a used corner).

    Raises:
        UserError: an output folder that cannot be written, unreadable inputs, too few
            usable views (:func:`bodyfit.calib.capture.calibrate`).
    """
    check_writable_dir(output.parent)
    check_writable_dir(coverage_path.parent)
    views, image_size = collect_views(inputs, BoardDetector(spec), settings)
    calibration = calibrate(views, image_size, settings, spec)
    covered = coverage_fraction(list(calibration.views), image_size)
    record = {
        **calibration.to_record(),
        "coverage_fraction": covered,
        "provenance": {
            "argv": argv,
            "inputs": list(inputs),
            "input_sha256": [file_sha256(path) for path in inputs],
            "bodyfit_version": bodyfit_version(),
            "opencv_version": cv2.__version__,
            "time": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        },
    }
    write_image(coverage_path, coverage_picture(list(calibration.views), image_size))
    write_atomic(output, (json.dumps(record, indent=2, allow_nan=False) + "\n").encode())
    return calibration, covered

"""The real photos of tests/data/real-photos, each with its silhouette and the photography
check's verdict, for docs/real-photos.md.

For each photo: the silhouette `calib silhouette` and `fitter run` take of it (the
``auto`` segmenter) tinted over it with its outline, the pose model's landmarks as dots,
written as a JPEG 480 px tall; and one Markdown table row: the photo, the picture, the
check's reading and its verdict as a front photo (problems, then warnings). A photo with
no person gets the line the silhouette step refuses it with.
Usage:

    python tools/real_photos_picture.py [--photos tests/data/real-photos] [-o docs/real-photos]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import cv2
import numpy as np

from bodyfit.calib.images import write_image
from bodyfit.calib.silhouette import photo_silhouette
from bodyfit.common.errors import UserError
from bodyfit.fitter.check.photos import check_view
from bodyfit.fitter.fit.person import upright_photo

HEIGHT_PX = 480
_TINT_BGR = np.array([60, 200, 60], np.float64)


def _picture(image: np.ndarray, mask: np.ndarray, landmarks: np.ndarray | None) -> np.ndarray:
    """The photo with the silhouette tinted green and outlined, and the landmarks as red
    dots, scaled to ``HEIGHT_PX`` tall."""
    picture = image.astype(np.float64)
    picture[mask] = 0.6 * picture[mask] + 0.4 * _TINT_BGR
    picture = picture.astype(np.uint8)
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)
    line = max(2, image.shape[0] // 400)
    cv2.drawContours(picture, contours, -1, (0, 0, 255), line, cv2.LINE_AA)
    if landmarks is not None:
        for x, y in landmarks[:, :2]:
            cv2.circle(picture, (int(round(x)), int(round(y))), 2 * line, (0, 0, 255), -1,
                       cv2.LINE_AA)
    scale = HEIGHT_PX / image.shape[0]
    return cv2.resize(picture, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)


def photo_row(path: Path, out_dir: Path) -> str:
    """Write ``out_dir/<name>.jpg`` of one photo; return its Markdown table row."""
    image = upright_photo(str(path), None)
    try:
        mask = photo_silhouette(path)
    except UserError as error:
        write_image(out_dir / f"{path.stem}.jpg", _picture(image, np.zeros(image.shape[:2], bool),
                                                           None))
        return f"| {path.name} | ![{path.stem}](real-photos/{path.stem}.jpg) | refused: {error} |"
    verdict = check_view("front", image, mask)
    write_image(out_dir / f"{path.stem}.jpg", _picture(image, mask, verdict.landmarks))
    said = ([f"**problem**: {line}" for line in verdict.problems]
            + [f"warning: {line}" for line in verdict.warnings]) or ["passes"]
    return (f"| {path.name} | ![{path.stem}](real-photos/{path.stem}.jpg) | "
            f"{verdict.summary()}<br>{'<br>'.join(said)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--photos", type=Path, default=Path("tests/data/real-photos"))
    parser.add_argument("-o", "--output", type=Path, default=Path("docs/real-photos"))
    args = parser.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    print("| photo | silhouette (green) and landmarks (red) | the check, as a front photo |")
    print("|---|---|---|")
    for path in sorted(args.photos.glob("*.jp*g")):
        print(photo_row(path, args.output))


if __name__ == "__main__":
    main()

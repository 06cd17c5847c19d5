"""Draw fitter/data/poses.png: the two poses to photograph, cut from a demo's photos.

    fitter demo -o out/demo
    python tools/poses_picture.py out/demo -o fitter/data/poses.png

Finds the person in DIR/front.png and DIR/side.png (the pixels whose colour differs from
the backdrop's, the median of the photo's border), cuts a panel around each, scaled so
that both people are --height-px tall, and sets the two side by side, labelled.
"""

import argparse
from pathlib import Path

import cv2
import numpy as np

LABELS = {"front": "front: A-pose", "side": "side: from the left, arms down"}


def person_box(photo: np.ndarray, threshold: float = 40.0) -> tuple[int, int, int, int]:
    """(top, bottom, left, right) pixel bounds of the person in an (H, W, 3) uint8 photo."""
    border = np.concatenate([photo[0], photo[-1], photo[:, 0], photo[:, -1]]).astype(np.float32)
    distance = np.linalg.norm(photo.astype(np.float32) - np.median(border, axis=0), axis=2)
    rows, cols = np.nonzero(distance > threshold)
    if rows.size == 0:
        raise SystemExit("poses_picture: error: no person found on the backdrop")
    return rows.min(), rows.max() + 1, cols.min(), cols.max() + 1


def panel(photo: np.ndarray, label: str, height_px: int, width_px: int,
          margin_px: int) -> np.ndarray:
    """The person scaled to height_px on a (height_px + 2 margins) x width_px cut, label below."""
    top, bottom, left, right = person_box(photo)
    scale = height_px / (bottom - top)
    half_w, pad = width_px / scale / 2, margin_px / scale
    centre = (left + right) / 2
    x0, x1 = max(int(centre - half_w), 0), min(int(centre + half_w), photo.shape[1])
    y0, y1 = max(int(top - pad), 0), min(int(bottom + pad), photo.shape[0])
    cut = cv2.resize(photo[y0:y1, x0:x1], (width_px, height_px + 2 * margin_px),
                     interpolation=cv2.INTER_AREA)
    strip = np.full((28, width_px, 3), 255, np.uint8)
    (text_w, _), _ = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, 0.45, 1)
    cv2.putText(strip, label, ((width_px - text_w) // 2, 19), cv2.FONT_HERSHEY_SIMPLEX, 0.45,
                (40, 40, 40), 1, cv2.LINE_AA)
    return np.vstack([cut, strip])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("demo_dir", type=Path, help="a fitter demo folder (front.png, side.png)")
    parser.add_argument("-o", "--output", type=Path, default=Path("fitter/data/poses.png"))
    parser.add_argument("--height-px", type=int, default=300, help="each person's height, pixels")
    args = parser.parse_args()
    panels = []
    for view, label in LABELS.items():
        photo = cv2.imread(str(args.demo_dir / f"{view}.png"), cv2.IMREAD_COLOR)
        if photo is None:
            raise SystemExit(f"poses_picture: error: cannot read {args.demo_dir / view}.png")
        panels.append(panel(photo, label, args.height_px, round(args.height_px * 0.85), 10))
    gap = np.full((panels[0].shape[0], 8, 3), 255, np.uint8)
    cv2.imwrite(str(args.output), np.hstack([panels[0], gap, panels[1]]))
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()

"""A photo a browser uploads, decoded and stored re-encoded.

Nothing a client sends is kept as sent: the bytes must decode as an image (Pillow, with its
decompression-bomb limit), and the pixels are written anew as a JPEG under a name the
server chose. Of the EXIF block only what a fit reads survives: the orientation and the
focal length's tags (:func:`bodyfit.calib.images.read_photo`); a phone's location and the
rest are dropped.
"""

from __future__ import annotations

import io
from pathlib import Path

from PIL import ExifTags, Image

from bodyfit.common.errors import UserError
from bodyfit.common.files import write_atomic

__all__ = ["MAX_UPLOAD_BYTES", "MAX_PIXELS", "store_photo"]

#: The largest photo upload accepted, bytes (a phone's 48-megapixel JPEG is about 15 MB).
MAX_UPLOAD_BYTES = 25 * 1024 * 1024
#: The most pixels an upload may decode to (a 64-megapixel photo; beyond is refused rather
#: than decoded: a small file can expand to gigabytes).
MAX_PIXELS = 64_000_000
#: The EXIF tags kept (:func:`bodyfit.calib.images.read_photo` reads them).
_KEPT_EXIF = (ExifTags.Base.FocalLengthIn35mmFilm, ExifTags.Base.FocalLength,
              ExifTags.Base.FocalPlaneXResolution, ExifTags.Base.FocalPlaneResolutionUnit)
_JPEG_QUALITY = 95


def _kept_exif(image: Image.Image) -> Image.Exif:
    exif = Image.Exif()
    try:
        given = image.getexif()
        orientation = given.get(ExifTags.Base.Orientation)
        fields = given.get_ifd(ExifTags.IFD.Exif)
    except Exception:  # a malformed block: nothing kept  # noqa: BLE001
        return exif
    if isinstance(orientation, int) and 1 <= orientation <= 8:
        exif[ExifTags.Base.Orientation] = orientation
    kept = {tag: fields[tag] for tag in _KEPT_EXIF if tag in fields}
    if kept:
        exif.get_ifd(ExifTags.IFD.Exif).update(kept)
    return exif


def store_photo(data: bytes, path: Path) -> tuple[int, int]:
    """Decode ``data`` as an image and write it re-encoded to ``path`` (a JPEG, with only
    the orientation and focal-length EXIF tags); returns its (width, height) in pixels.

    Raises:
        UserError: too large, not an image, cut short or corrupt, or too many pixels.
    """
    if len(data) > MAX_UPLOAD_BYTES:
        raise UserError(f"the photo is {len(data) / 1e6:.0f} MB; at most "
                        f"{MAX_UPLOAD_BYTES / 1e6:.0f} MB is accepted: send a smaller one")
    if not data:
        raise UserError("the photo is empty: take or choose it again")
    try:
        with Image.open(io.BytesIO(data)) as image:
            if image.width * image.height > MAX_PIXELS:
                raise UserError(f"the photo has {image.width * image.height / 1e6:.0f} "
                                f"megapixels; at most {MAX_PIXELS / 1e6:.0f} are accepted")
            image.load()
            exif = _kept_exif(image)
            rgb = image.convert("RGB")
    except UserError:
        raise
    except Image.DecompressionBombError:
        raise UserError("the photo has too many pixels to be read") from None
    except Exception:  # Pillow raises many kinds on a corrupt file  # noqa: BLE001
        raise UserError("the file is not a readable photo (a JPEG or PNG from the camera); "
                        "take or choose it again") from None
    out = io.BytesIO()
    rgb.save(out, "JPEG", quality=_JPEG_QUALITY, exif=exif)
    write_atomic(path, out.getvalue())
    return rgb.width, rgb.height

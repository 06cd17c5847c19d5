"""`fitter serve`'s web app: Starlette routes over the store (:mod:`.store`) and the fit
queue (:mod:`.queue`).

Starlette (with uvicorn to serve it, python-multipart to read uploads) is the small,
well-kept ASGI toolkit under FastAPI; the app needs its routing, forms, responses and test
client, not FastAPI's schema layer.

Who can reach it: with a ``token`` (``fitter serve --host`` other than the machine's own),
every request needs the cookie the access link sets (``/?token=...``, printed at start and
shown as a QR code on the page); without one, the app is for this machine only.
"""

from __future__ import annotations

import contextlib
import csv
import importlib.resources
import io
import json
import math
import secrets
import shutil
import threading
import uuid
from pathlib import Path

import segno
from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.middleware import Middleware
from starlette.middleware.base import BaseHTTPMiddleware
from starlette.requests import Request
from starlette.responses import (FileResponse, HTMLResponse, JSONResponse, PlainTextResponse,
                                 RedirectResponse, Response)
from starlette.routing import Route

from bodyfit.calib.boards import parse_board
from bodyfit.calib.camera_capture import capture_camera
from bodyfit.calib.capture import CaptureSettings, describe_views
from bodyfit.common.errors import UserError
from bodyfit.fitter.batch.engines import WorkerSetup
from bodyfit.fitter.fit.person import PersonInputs, checked_photo
from bodyfit.fitter.measure.measurements import MEASUREMENTS
from bodyfit.fitter.serve.pages import (PICTURES, RESULT_FILES, as_fields, cameras_page,
                                        fit_page, measure_page, people_page, person_page)
from bodyfit.fitter.serve.queue import RESULT, FitQueue, camera_file, fit_folder
from bodyfit.fitter.serve.store import Store
from bodyfit.fitter.serve.uploads import MAX_UPLOAD_BYTES, store_photo

__all__ = ["COOKIE", "create_app"]

COOKIE = "bodyfit_token"
_MAX_PERSON = 100
_MAX_BOARD_PHOTOS = 40
_VIEWS = ("front", "side")


class _Studio:
    """The app's state: the data folder, the store, the queue, the uploads not yet fitted
    (their server-made names, by the random key given to the browser)."""

    def __init__(self, data: Path, store: Store, queue: FitQueue):
        self.data, self.store, self.queue = data, store, queue
        self.uploads: dict[str, tuple[str, Path]] = {}  # key -> (view, path)
        self.checking = threading.Lock()  # one check at a time: the pose model is shared

    def check(self, inputs: PersonInputs, view: str):
        with self.checking:
            return checked_photo(inputs, view)


def _problems(lines: list[str], status: int = 400) -> JSONResponse:
    return JSONResponse({"problems": lines}, status_code=status)


def _too_large(request: Request, files: int) -> None:
    """UserError when the request is larger than ``files`` uploads may be."""
    length = request.headers.get("content-length", "")
    if length.isdigit() and int(length) > files * MAX_UPLOAD_BYTES + 65536:
        raise UserError(f"the upload is {int(length) / 1e6:.0f} MB; at most "
                        f"{MAX_UPLOAD_BYTES / 1e6:.0f} MB a photo is accepted: send smaller "
                        "ones")


async def _file_bytes(upload) -> bytes:
    if upload is None or isinstance(upload, str):
        raise UserError("no photo was sent: take or choose one")
    return await upload.read(MAX_UPLOAD_BYTES + 1)


def _camera_of(studio: "_Studio", given: str | None) -> tuple[int | None, str | None]:
    """(camera id, its camera.json) of the form's ``camera`` field; (None, None): the
    photos' EXIF focal length."""
    if not given:
        return None, None
    if not given.isdigit() or studio.store.camera(int(given)) is None:
        raise UserError("no such camera: choose a registered one, or none")
    return int(given), str(camera_file(studio.data, int(given)))


async def check_photo(request: Request) -> JSONResponse:
    """Store one photo and run the photography check on it: its problems and warnings, and
    the key that names it in the fit's request when it passes."""
    studio: _Studio = request.app.state.studio
    view = request.path_params["view"]
    if view not in _VIEWS:
        return _problems([f"no such view {view!r}: front or side"], 404)
    path = studio.data / "uploads" / f"{uuid.uuid4().hex}.jpg"
    try:
        _too_large(request, 1)
        form = await request.form(max_files=1, max_fields=4)
        _, camera = _camera_of(studio, form.get("camera"))
        store_photo(await _file_bytes(form.get("photo")), path)
        # the check reads no stature
        inputs = PersonInputs(str(path), str(path), math.nan, camera)
        verdict = await run_in_threadpool(studio.check, inputs, view)
    except UserError as error:
        path.unlink(missing_ok=True)
        return JSONResponse({"upload": None, "problems": [str(error)], "warnings": []})
    if verdict.problems:
        path.unlink(missing_ok=True)
        return JSONResponse({"upload": None, "problems": list(verdict.problems),
                             "warnings": list(verdict.warnings)})
    key = secrets.token_hex(16)
    studio.uploads[key] = (view, path)
    return JSONResponse({"upload": key, "problems": [], "warnings": list(verdict.warnings),
                         "summary": verdict.summary()})


def _number(form, name: str, label: str, required: bool) -> float | None:
    text = (form.get(name) or "").strip()
    if not text:
        if required:
            raise UserError(f"give the {label}")
        return None
    try:
        return float(text)
    except ValueError:
        raise UserError(f"the {label} must be a number, got {text!r}") from None


async def start_fit(request: Request) -> JSONResponse:
    """Queue a fit of the person the form gives, with two checked photos' keys."""
    studio: _Studio = request.app.state.studio
    form = await request.form(max_files=0, max_fields=10)
    person = " ".join((form.get("person") or "").split())
    try:
        if not person or len(person) > _MAX_PERSON or not person.isprintable():
            raise UserError(f"give the person's id or name (1-{_MAX_PERSON} characters)")
        uploads = {}
        for view in _VIEWS:
            given = studio.uploads.get(form.get(view) or "")
            if given is None or given[0] != view:
                raise UserError(f"take the {view} photo (and let it pass the check) first")
            uploads[view] = given[1]
        camera_id, camera = _camera_of(studio, form.get("camera"))
        inputs = PersonInputs(str(uploads["front"]), str(uploads["side"]),
                              _number(form, "height_cm", "stature in centimetres", True),
                              camera, sex=form.get("sex") or "unknown",
                              mass_kg=_number(form, "mass_kg", "mass in kilograms", False))
        inputs.validate()
    except UserError as error:
        return _problems([as_fields(str(error))])
    fit_id = studio.store.add_fit(person, inputs.height_cm, inputs.sex, inputs.mass_kg,
                                  camera_id)
    folder = fit_folder(studio.data, fit_id)
    folder.mkdir(parents=True)
    for view in _VIEWS:
        shutil.move(uploads[view], folder / f"{view}.jpg")
        del studio.uploads[form.get(view)]
    studio.queue.submit(studio.store.fit(fit_id))
    return JSONResponse({"fit": fit_id})


def _record(request: Request):
    studio: _Studio = request.app.state.studio
    return studio, studio.store.fit(request.path_params["fit"])


async def fit_status(request: Request) -> JSONResponse:
    studio, record = _record(request)
    if record is None:
        return _problems(["no such fit"], 404)
    return JSONResponse(studio.queue.progress(record).as_json() | {"reason": record.reason})


async def show_fit(request: Request) -> Response:
    studio, record = _record(request)
    if record is None:
        return PlainTextResponse("no such fit", 404)
    photos = {}
    if record.state == "done":
        photos = json.loads((fit_folder(studio.data, record.fit_id) / RESULT / "run.json")
                            .read_text())["photos"]
    camera = None if record.camera is None else studio.store.camera(record.camera)["name"]
    return HTMLResponse(fit_page(record, photos, camera))


async def fit_file(request: Request) -> Response:
    studio, record = _record(request)
    name = request.path_params["name"]
    if record is None or record.state != "done" or name not in RESULT_FILES | PICTURES:
        return PlainTextResponse("no such file", 404)
    return FileResponse(fit_folder(studio.data, record.fit_id) / RESULT / name,
                        filename=f"{record.fit_id}-{name}" if name in RESULT_FILES else None)


async def people(request: Request) -> HTMLResponse:
    query = request.query_params.get("q", "")[:_MAX_PERSON]
    return HTMLResponse(people_page(request.app.state.studio.store.people(query), query))


async def person(request: Request) -> Response:
    name = request.path_params["person"]
    fits = request.app.state.studio.store.fits(name)
    if not fits:
        return PlainTextResponse("no one of that id or name", 404)
    return HTMLResponse(person_page(fits[0].person, fits))


async def export(request: Request) -> Response:
    """Every finished fit, one row each: who, when, the inputs, each measurement and ±."""
    out = io.StringIO()
    writer = csv.writer(out)
    names = [name for name, _ in MEASUREMENTS.values()]
    writer.writerow(["person", "fit", "created", "height_cm", "sex", "mass_kg"]
                    + [f"{n}_{what}" for n in names for what in ("mm", "spread_mm")])
    for r in request.app.state.studio.store.fits(states=("done",)):
        values = [f"{r.measurements[n][k]:.1f}" if n in r.measurements else ""
                  for n in names for k in ("value_mm", "spread_mm")]
        writer.writerow([r.person, r.fit_id, r.created, f"{r.height_cm:g}", r.sex,
                         "" if r.mass_kg is None else f"{r.mass_kg:g}", *values])
    return Response(out.getvalue(), media_type="text/csv",
                    headers={"content-disposition": "attachment; filename=bodyfit-studio.csv"})


async def home(request: Request) -> HTMLResponse:
    link = request.app.state.access_url
    access = ("" if link is None else
              "<details class=qr><summary>Open this page on a phone</summary>"
              f"{segno.make(link).svg_inline(scale=4)}<p>or go to <code>{link}</code></p>"
              "</details>")
    return HTMLResponse(measure_page(access, request.app.state.studio.store.cameras()))


async def cameras(request: Request) -> HTMLResponse:
    return HTMLResponse(cameras_page(request.app.state.studio.store.cameras()))


async def calibrate(request: Request) -> JSONResponse:
    """Calibrate a camera from the board photos of the form (``calib capture``) and
    register it under the form's name: the views used and rejected, the RMS error."""
    studio: _Studio = request.app.state.studio
    work = studio.data / "cameras" / f"new-{uuid.uuid4().hex}"
    try:
        _too_large(request, _MAX_BOARD_PHOTOS)
        form = await request.form(max_files=_MAX_BOARD_PHOTOS, max_fields=8)
        name = " ".join((form.get("name") or "").split())
        if not name or len(name) > _MAX_PERSON or not name.isprintable():
            raise UserError(f"give the camera a name (1-{_MAX_PERSON} characters)")
        if any(row["name"].lower() == name.lower() for row in studio.store.cameras()):
            raise UserError(f"a camera is registered as {name!r} already: choose another name")
        square = _number(form, "square_mm", "printed square's side in millimetres", True)
        spec = parse_board(form.get("board") or "", square, None, None)
        uploads = form.getlist("photos")
        if not uploads:
            raise UserError("choose the board photos")
        work.mkdir(parents=True)
        given = {}  # stored path -> the name the browser gave (shown as text only)
        for i, upload in enumerate(uploads):
            path = work / f"board_{i + 1:02d}.jpg"
            store_photo(await _file_bytes(upload), path)
            given[str(path)] = str(getattr(upload, "filename", "") or path.name)[:_MAX_PERSON]
        paths = list(given)
        calibration, covered = await run_in_threadpool(
            capture_camera, paths, spec, CaptureSettings(), work / "camera.json",
            work / "coverage.png", ["fitter serve", "calibrate", name])
    except UserError as error:
        shutil.rmtree(work, ignore_errors=True)
        return _problems([as_fields(str(error))])
    views = describe_views(calibration.views)
    camera_id = studio.store.add_camera(name, calibration.rms_px, views)
    work.rename(camera_file(studio.data, camera_id).parent)
    return JSONResponse({"camera": camera_id, "name": name, "views": views,
                         "rms_px": round(calibration.rms_px, 3), "coverage": round(covered, 3),
                         "each": [{"photo": given[view.source], "status": view.status.value,
                                   "error_px": view.error_px} for view in calibration.views]})


async def poses(request: Request) -> FileResponse:
    return FileResponse(importlib.resources.files("bodyfit.fitter.data") / "poses.png")


class _TokenGate(BaseHTTPMiddleware):
    """Every request needs the access cookie; the access link (``?token=``) sets it."""

    async def dispatch(self, request: Request, call_next):
        token = request.app.state.token
        if token is None:
            return await call_next(request)
        given = request.query_params.get("token")
        if given is not None and secrets.compare_digest(given, token):
            answer = RedirectResponse(request.url.path, 303)
            answer.set_cookie(COOKIE, token, httponly=True, samesite="strict")
            return answer
        if secrets.compare_digest(request.cookies.get(COOKIE, ""), token):
            return await call_next(request)
        return PlainTextResponse("this studio page needs its access link: open the link, or "
                                 "scan the QR code, that fitter serve printed", 403)


def create_app(data: Path, setup: WorkerSetup, workers: int, token: str | None = None,
               access_url: str | None = None) -> Starlette:
    """The app over the studio folder ``data`` (created), fitting on ``workers`` processes
    (``setup``: :class:`~bodyfit.fitter.batch.engines.WorkerSetup`); ``token``: the secret
    every request needs (None: none), ``access_url``: the link that gives it.

    Raises:
        UserError: ``data``'s database cannot be opened.
    """

    data = Path(data)
    shutil.rmtree(data / "uploads", ignore_errors=True)  # the last run's, never fitted
    (data / "uploads").mkdir(parents=True)
    store = Store(data / "studio.sqlite")

    @contextlib.asynccontextmanager
    async def lifespan(app):
        app.state.studio = _Studio(data, store, FitQueue(store, data, workers, setup))
        try:
            yield
        finally:
            app.state.studio.queue.close()

    app = Starlette(routes=[
        Route("/", home), Route("/poses.png", poses),
        Route("/api/photos/{view}", check_photo, methods=["POST"]),
        Route("/api/fits", start_fit, methods=["POST"]),
        Route("/api/fits/{fit:int}", fit_status), Route("/fits/{fit:int}", show_fit),
        Route("/fits/{fit:int}/files/{name}", fit_file),
        Route("/people", people), Route("/people/{person}", person),
        Route("/export.csv", export), Route("/cameras", cameras),
        Route("/api/cameras", calibrate, methods=["POST"]),
    ], middleware=[Middleware(_TokenGate)], lifespan=lifespan)
    app.state.token, app.state.access_url = token, access_url
    return app

"""`fitter serve`: uploads re-encoded, the store, the app's routes through Starlette's test
client (no network), and a whole measurement: a camera calibrated from the demo's board
photos, the demo's photos checked and fitted, the report and the person's history."""

import csv
import io
import json
import re
import sqlite3
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import ExifTags, Image
from starlette.testclient import TestClient

from bodyfit.common.errors import UserError
from bodyfit.common.files import file_sha256
from bodyfit.fitter.batch.engines import WorkerSetup
from bodyfit.fitter.batch.job import WORKER_EXIT_HOOK
from bodyfit.fitter.demo.example import write_scene
from bodyfit.fitter.measure.measurements import MEASUREMENTS
from bodyfit.fitter.model.cache import active_model_path
from bodyfit.fitter.serve import uploads
from bodyfit.fitter.serve.app import COOKIE, create_app
from bodyfit.fitter.serve.store import Store

REAL = Path(__file__).parents[1] / "data" / "real-photos"
_GPS = 0x8825


def _jpeg(size=(60, 80), exif=None) -> bytes:
    out = io.BytesIO()
    Image.new("RGB", size, (120, 90, 60)).save(out, "JPEG", exif=exif or Image.Exif())
    return out.getvalue()


def test_upload_is_re_encoded_keeping_only_orientation_and_focal_length(tmp_path):
    exif = Image.Exif()
    exif[ExifTags.Base.Orientation] = 6
    exif[ExifTags.Base.Make] = "PhoneCo"
    exif.get_ifd(ExifTags.IFD.Exif)[ExifTags.Base.FocalLengthIn35mmFilm] = 26
    exif.get_ifd(_GPS)[2] = (51.0, 30.0, 0.0)
    path = tmp_path / "photo.jpg"
    assert uploads.store_photo(_jpeg(exif=exif), path) == (60, 80)
    with Image.open(path) as stored:
        kept = stored.getexif()
        assert stored.format == "JPEG"
        assert kept[ExifTags.Base.Orientation] == 6
        assert kept.get_ifd(ExifTags.IFD.Exif)[ExifTags.Base.FocalLengthIn35mmFilm] == 26
        assert ExifTags.Base.Make not in kept and not kept.get_ifd(_GPS)


@pytest.mark.parametrize("data, message", [
    (b"", "the photo is empty"),
    (b"GIF89a not really", "not a readable photo"),
    (_jpeg()[:300], "not a readable photo"),
])
def test_bad_uploads_are_refused_with_one_line(tmp_path, data, message):
    with pytest.raises(UserError, match=message):
        uploads.store_photo(data, tmp_path / "photo.jpg")
    assert not (tmp_path / "photo.jpg").exists()


def test_uploads_over_the_limits_are_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(uploads, "MAX_UPLOAD_BYTES", 100)
    with pytest.raises(UserError, match="at most 0 MB"):
        uploads.store_photo(_jpeg(), tmp_path / "photo.jpg")
    monkeypatch.setattr(uploads, "MAX_UPLOAD_BYTES", 10 ** 6)
    monkeypatch.setattr(uploads, "MAX_PIXELS", 60 * 79)
    with pytest.raises(UserError, match="megapixels"):
        uploads.store_photo(_jpeg(), tmp_path / "photo.jpg")


def test_store_keeps_people_and_fits_across_a_restart(tmp_path):
    store = Store(tmp_path / "studio.sqlite")
    first = store.add_fit("Ann 100%", 172.0, "female", None, None)
    store.add_fit("ann 100%", 172.5, "female", 61.0, None)
    store.add_fit("Bob_2", 180.0, "male", None, None)
    store.set_state(first, "done", seconds=12.0, measurements={"waist": {"value_mm": 800.0}})
    again = Store(tmp_path / "studio.sqlite")
    assert [f.person for f in again.fits("ANN 100%")] == ["Ann 100%", "Ann 100%"]
    assert again.fit(first).measurements == {"waist": {"value_mm": 800.0}}
    assert [p for p, _, _ in again.people("100%")] == ["Ann 100%"]
    assert [p for p, _, _ in again.people("_")] == ["Bob_2"]  # LIKE's wildcards are literal
    assert [(p, n) for p, n, _ in again.people("")] == [("Bob_2", 1), ("Ann 100%", 2)]
    with pytest.raises(ValueError):
        again.set_state(first, "lost")


@pytest.fixture(scope="module")
def scene(body_model, tmp_path_factory):
    return write_scene(body_model, tmp_path_factory.mktemp("demo"))


def _app(folder: Path, token=None):
    return create_app(folder, WorkerSetup(file_sha256(active_model_path())), 1, token,
                      None if token is None else f"http://192.0.2.1:8000/?token={token}")


def _photo(path) -> dict:
    return {"photo": (Path(path).name, Path(path).read_bytes(), "image/png")}


@pytest.fixture()
def client(tmp_path):
    with TestClient(_app(tmp_path / "studio")) as client:
        yield client


def test_the_page_opens_the_camera_on_a_phone(client):
    page = client.get("/").text
    assert page.count("accept='image/*' capture=environment") == 2
    assert "<img src='/poses.png'" in page and client.get("/poses.png").status_code == 200
    assert "http://" not in page and "https://" not in page  # nothing from outside


def test_bad_photos_get_the_checks_one_line_and_no_upload(client, scene, tmp_path):
    cases = {"front": (b"not an image", "not a readable photo"),
             "side": ((REAL / "background.jpeg").read_bytes(), "no person")}
    for view, (data, message) in cases.items():
        got = client.post(f"/api/photos/{view}", files={"photo": ("x.jpg", data)}).json()
        assert got["upload"] is None and len(got["problems"]) == 1, got
        assert message in got["problems"][0] and "\n" not in got["problems"][0]
    # the side photo given as the front: the check's own reason
    got = client.post("/api/photos/front", files=_photo(scene.side)).json()
    assert got["upload"] is None and got["problems"]
    assert client.post("/api/photos/back", files=_photo(scene.side)).status_code == 404
    assert "no photo was sent" in client.post("/api/photos/front").json()["problems"][0]
    assert not any((tmp_path / "studio" / "uploads").iterdir())


def test_a_fit_needs_its_fields_and_two_checked_photos(client, scene, tmp_path):
    front = client.post("/api/photos/front", files=_photo(scene.front)).json()
    side = client.post("/api/photos/side", files=_photo(scene.side)).json()
    assert front["upload"] and side["upload"] and front["summary"].startswith("the front")
    good = {"person": "Ann", "height_cm": "172", "sex": "female", "front": front["upload"],
            "side": side["upload"]}
    cases = [({"person": "  "}, "give the person's id or name"),
             ({"height_cm": ""}, "give the stature in centimetres"),
             ({"height_cm": "68"}, "the stature must be a stature in centimetres, 100-250"),
             ({"height_cm": "tall"}, "must be a number"),
             ({"mass_kg": "150000"}, "the mass must be a body mass in kilograms"),
             ({"sex": "x"}, "the sex must be one of female, male, unknown"),
             ({"camera": "7"}, "no such camera"),
             ({"front": side["upload"]}, "take the front photo"),
             ({"side": "../../studio.sqlite"}, "take the side photo")]
    for change, message in cases:
        answer = client.post("/api/fits", data=good | change)
        assert answer.status_code == 400 and message in answer.json()["problems"][0], change
    assert not (tmp_path / "studio" / "fits").exists()  # nothing half-written
    assert client.get("/people").text.count("<td><a href") == 0


def test_a_calibration_without_boards_registers_nothing(client, scene, tmp_path):
    form = {"name": "phone", "board": "chessboard:9x6", "square_mm": "25"}
    photos = [("photos", ("front.png", scene.front.read_bytes(), "image/png"))]
    cases = [(form, photos, "no board found in any of the 1 views; check the board"), (form | {"board": "chess:9"}, photos, "board"),
             (form | {"square_mm": ""}, photos, "give the printed square's side"),
             (form | {"name": ""}, photos, "give the camera a name"), (form, [], "choose")]
    for fields, files, message in cases:
        answer = client.post("/api/cameras", data=fields, files=files)
        assert answer.status_code == 400 and message in answer.json()["problems"][0], fields
    assert not any((tmp_path / "studio" / "cameras").glob("*"))
    assert "No camera registered" in client.get("/cameras").text


def test_files_and_people_are_not_paths(client):
    assert client.get("/fits/1").status_code == 404
    assert client.get("/fits/1/files/..%2F..%2Fstudio.sqlite").status_code == 404
    assert client.get("/people/..%2Fstudio").status_code == 404
    assert client.get("/api/fits/1").json()["problems"] == ["no such fit"]


def test_off_this_machine_every_request_needs_the_access_link(tmp_path):
    with TestClient(_app(tmp_path / "studio", token="s3cret"), base_url="http://studio") as c:
        assert c.get("/").status_code == 403 and c.get("/export.csv").status_code == 403
        assert c.get("/?token=wrong").status_code == 403
        answer = c.get("/?token=s3cret", follow_redirects=False)
        assert answer.status_code == 303 and answer.headers["location"] == "/"
        assert "httponly" in answer.headers["set-cookie"].lower()
        page = c.get("/")  # the cookie now set
        assert page.status_code == 200 and "<svg" in page.text and "token=s3cret" in page.text
    with TestClient(_app(tmp_path / "studio", token="s3cret"), cookies={COOKIE: "s3cret"}) as c:
        assert c.get("/people").status_code == 200


def _wait(client, fit_id: int, seconds: float = 300.0) -> dict:
    end = time.time() + seconds
    while time.time() < end:
        status = client.get(f"/api/fits/{fit_id}").json()
        if status["state"] in ("done", "failed"):
            return status
        assert status["state"] in ("queued", "fitting") and status["left_s"] >= 0
        time.sleep(0.5)
    raise AssertionError(f"fit {fit_id} not finished in {seconds} s")


def test_a_person_measured_twice_through_a_calibrated_camera(scene, tmp_path):
    data = tmp_path / "studio"
    with TestClient(_app(data)) as client:
        boards = [("photos", (p.name, p.read_bytes(), "image/png")) for p in scene.board_photos]
        camera = client.post("/api/cameras", data={"name": "demo phone", "square_mm": "25",
                                                   "board": scene.settings.board},
                             files=boards).json()
        assert camera["views"].startswith(f"{len(scene.board_photos) - 2} used, 2 rejected")
        assert camera["rms_px"] < 0.2
        again = client.post("/api/cameras", data={"name": "Demo Phone", "square_mm": "25",
                                                  "board": scene.settings.board}, files=boards)
        assert "registered as 'Demo Phone' already" in again.json()["problems"][0]
        assert "demo phone" in client.get("/cameras").text
        fits = []
        for _ in range(2):
            keys = {view: client.post(f"/api/photos/{view}", data={"camera": camera["camera"]},
                                      files=_photo(getattr(scene, view))).json()["upload"]
                    for view in ("front", "side")}
            fits.append(client.post("/api/fits", data={
                "person": "Ann", "height_cm": f"{scene.truth['O'] / 10:g}", "sex": "unknown",
                "camera": str(camera["camera"]), **keys}).json()["fit"])
        keys = {view: client.post(f"/api/photos/{view}", data={"camera": camera["camera"]},
                                  files=_photo(getattr(scene, view))).json()["upload"]
                for view in ("front", "side")}
        heavy = client.post("/api/fits", data={  # pounds for kilograms: refused after its fit
            "person": "Ann", "height_cm": f"{scene.truth['O'] / 10:g}", "sex": "unknown",
            "mass_kg": "250", "camera": str(camera["camera"]), **keys}).json()["fit"]
        for fit_id in fits:
            assert _wait(client, fit_id)["state"] == "done"
        refused = _wait(client, heavy)
        assert refused["state"] == "failed" and re.fullmatch(
            r"the mass 250 is \d\.\d times what the body in the photos weighs \(about \d+ "
            r"kg\): give this person's mass in kilograms, or leave it out", refused["reason"])
        page = client.get(f"/fits/{fits[0]}").text
        assert "Camera: demo phone (calibrated)" in page
        shown = {name: float(value) for name, value in
                 re.findall(r"data-measurement='(\w+)'>([\d.]+)<", page)}
        stored = json.loads((data / "fits" / str(fits[0]) / "result" / "measurements.json")
                            .read_text())["measurements"]
        assert shown == {n: round(v["value_mm"] / 10, 1) for n, v in stored.items()}
        # the demo's body, measured as `fitter demo` measures it (about 1 mm there)
        errors = [abs(shown[MEASUREMENTS[k][0]] * 10 - scene.truth[k]) for k in "CDEFLP"]
        assert np.mean(errors) < 6.0, errors
        for name in ("mesh.obj", "measurements.csv", "photo_front.png", "body_views.png"):
            assert client.get(f"/fits/{fits[0]}/files/{name}").status_code == 200
        history = client.get("/people/ann").text
        assert history.count("(+0.0)") == len(MEASUREMENTS)  # the same photos again
        rows = list(csv.DictReader(io.StringIO(client.get("/export.csv").text)))
        assert [r["fit"] for r in rows] == [str(f) for f in fits]
        assert float(rows[0]["waist_circumference_mm"]) == pytest.approx(
            stored["waist_circumference"]["value_mm"], abs=0.05)
    # a fit queued when the server stopped is fitted at the next start
    store = Store(data / "studio.sqlite")
    queued = store.add_fit("Bo", scene.truth["O"] / 10, "unknown", None, None)
    folder = data / "fits" / str(queued)
    folder.mkdir()
    for view in ("front", "side"):
        (folder / f"{view}.jpg").write_bytes((data / "fits" / str(fits[0]) / f"{view}.jpg")
                                             .read_bytes())
    with TestClient(_app(data)) as client:
        assert _wait(client, queued)["state"] == "done"
        # the re-encoded PNGs state no focal length
        assert "Camera: assumed: a phone&#x27;s main camera" in client.get(f"/fits/{queued}").text
    assert sqlite3.connect(data / "studio.sqlite").execute(
        "SELECT COUNT(*) FROM fits WHERE state = 'done'").fetchone() == (3,)


def test_a_worker_that_dies_fails_its_fit_only(scene, tmp_path, monkeypatch):
    monkeypatch.setenv(WORKER_EXIT_HOOK, "1")  # the worker fitting fit 1 exits at once
    with TestClient(_app(tmp_path / "studio")) as client:
        fits = []
        for _ in range(2):
            keys = {view: client.post(f"/api/photos/{view}", files=_photo(getattr(scene, view)))
                    .json()["upload"] for view in ("front", "side")}
            fits.append(client.post("/api/fits", data={
                "person": "Ann", "height_cm": f"{scene.truth['O'] / 10:g}", **keys}).json()["fit"])
        first, second = (_wait(client, fit_id) for fit_id in fits)
        assert first["state"] == "failed" and "worker process died" in first["reason"]
        assert second["state"] == "done"
        assert "worker process died" in client.get(f"/fits/{fits[0]}").text

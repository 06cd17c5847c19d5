"""The studio's HTML pages: measure a person, a fit's progress and report, the people.

Plain HTML with a little script (no outside resources: the studio's network may have no
internet); every value a person typed is escaped. Sized for a phone's screen first.
"""

from __future__ import annotations

import html
from urllib.parse import quote

from bodyfit.fitter.fit.facing import side_text
from bodyfit.fitter.measure.measurements import MEASUREMENTS
from bodyfit.fitter.serve.store import FitRecord

__all__ = ["page", "measure_page", "fit_page", "people_page", "person_page", "cameras_page",
           "as_fields", "RESULT_FILES", "PICTURES"]

#: `fitter run`'s options, as the page's fields are called.
_FIELDS = {"--height-cm": "the stature", "--mass-kg": "the mass", "--sex": "the sex",
           "--board": "the board", "--square-mm": "the square's side"}


def as_fields(line: str) -> str:
    """A one-line error with the command line's option names as the page's fields."""
    for option, field in _FIELDS.items():
        line = line.replace(option, field)
    return line


#: The fit's outputs offered for download, and the report's pictures (file -> label).
RESULT_FILES = {"mesh.obj": "mesh (OBJ)", "mesh.ply": "mesh (PLY)",
                "measurements.csv": "measurements (CSV)",
                "measurements.json": "measurements (JSON)", "report.html": "full report"}
PICTURES = {"photo_front.png": "front photo with the fitted outline",
            "photo_side.png": "side photo with the fitted outline",
            "body_views.png": "the fitted body from three angles"}

_STYLE = """
body{font-family:system-ui,sans-serif;margin:0;color:#222;background:#fafafa}
header{background:#24425f;color:#fff;padding:.6em 1em;display:flex;gap:1.2em;
 flex-wrap:wrap;align-items:baseline}
header a{color:#fff}header strong{font-size:1.2em}
main{max-width:60em;margin:auto;padding:1em}
label{display:block;margin:.5em 0}input,select,button{font-size:1em;padding:.4em}
input[type=text],input[type=number],select{width:100%;max-width:20em;box-sizing:border-box}
.photos{display:flex;flex-wrap:wrap;gap:1em}.photo{flex:1 1 16em;border:1px solid #ccc;
 padding:.6em;background:#fff}.photo img{max-width:100%;max-height:14em}
.ok{color:#176b2c}.bad{color:#a4161a}.warn{color:#8a5a00}
button.go{background:#24425f;color:#fff;border:0;padding:.6em 1.4em;margin-top:1em}
button:disabled{opacity:.4}table{border-collapse:collapse}
td,th{padding:.25em .6em;border-bottom:1px solid #ddd;text-align:left}
td.num{text-align:right;font-variant-numeric:tabular-nums}
.pictures img{max-width:100%;max-height:30em;border:1px solid #ccc}
.pictures{display:flex;flex-wrap:wrap;gap:.6em}.pictures figure{margin:0;flex:1 1 14em}
.qr svg{width:12em;height:12em}
"""


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def page(title: str, body: str, script: str = "") -> str:
    """A whole page: the header's links, ``body`` (HTML) and ``script`` (JavaScript)."""
    return (f"<!doctype html><html lang=en><head><meta charset=utf-8>"
            f"<meta name=viewport content='width=device-width,initial-scale=1'>"
            f"<title>{_e(title)} - bodyfit studio</title><style>{_STYLE}</style></head><body>"
            f"<header><strong>bodyfit studio</strong><a href='/'>Measure</a>"
            f"<a href='/people'>People</a><a href='/cameras'>Cameras</a>"
            f"<a href='/export.csv'>Export CSV</a></header>"
            f"<main><h1>{_e(title)}</h1>{body}</main>"
            + (f"<script>{script}</script>" if script else "") + "</body></html>")


_MEASURE_SCRIPT = """
const uploads = {};
function ready() {
  document.getElementById('go').disabled = !(uploads.front && uploads.side);
}
async function check(view, input) {
  const box = document.getElementById(view + '-verdict');
  const img = document.getElementById(view + '-img');
  delete uploads[view]; ready();
  if (!input.files.length) return;
  img.src = URL.createObjectURL(input.files[0]); img.hidden = false;
  box.className = ''; box.textContent = 'checking...';
  const form = new FormData(); form.append('photo', input.files[0]);
  form.append('camera', document.getElementById('camera').value);
  const answer = await fetch('/api/photos/' + view, {method: 'POST', body: form});
  const got = await answer.json();
  box.innerHTML = '';
  for (const [kind, lines] of [['bad', got.problems], ['warn', got.warnings]]) {
    for (const line of lines) {
      const p = document.createElement('p'); p.className = kind; p.textContent = line;
      box.appendChild(p);
    }
  }
  if (got.upload) {
    uploads[view] = got.upload;
    const p = document.createElement('p'); p.className = 'ok';
    p.textContent = 'passes the check: ' + got.summary; box.prepend(p);
  }
  document.getElementById(view + '-retake').hidden = false;
  ready();
}
for (const view of ['front', 'side']) {
  const input = document.getElementById(view + '-file');
  input.addEventListener('change', () => check(view, input));
  document.getElementById(view + '-retake').addEventListener('click', () => {
    input.value = ''; input.click();
  });
}
document.getElementById('measure').addEventListener('submit', async (event) => {
  event.preventDefault();
  const form = new FormData(event.target);
  form.delete('front_file'); form.delete('side_file');
  form.append('front', uploads.front); form.append('side', uploads.side);
  const answer = await fetch('/api/fits', {method: 'POST', body: form});
  const got = await answer.json();
  if (got.fit) { location.href = '/fits/' + got.fit; return; }
  document.getElementById('error').textContent = got.problems.join(' ');
});
"""


def _photo_box(view: str, what: str) -> str:
    return (f"<div class=photo><h3>{what}</h3>"
            f"<input type=file id={view}-file name={view}_file accept='image/*' "
            f"capture=environment aria-label='{view} photo'>"
            f"<img id={view}-img alt='the {view} photo' hidden>"
            f"<div id={view}-verdict></div>"
            f"<button type=button id={view}-retake hidden>Retake</button></div>")


def _camera_choice(cameras) -> str:
    options = "".join(f"<option value={row['id']}>{_e(row['name'])} (RMS "
                      f"{row['rms_px']:.2f} px)</option>" for row in cameras)
    return ("<label>Camera <select name=camera id=camera><option value=''>the photo's focal "
            f"length (EXIF)</option>{options}</select></label>")


def measure_page(access: str = "", cameras=()) -> str:
    """The page to measure a person: their id, stature, sex and mass, the camera (one of
    ``cameras``, the store's rows, or none), and the two photos, each checked as it is
    taken. ``access``: HTML shown first (the phone's link)."""
    body = (access
            + "<form id=measure><label>Id or name <input type=text name=person required "
            "maxlength=100 autocomplete=off></label>"
            "<label>Stature, cm <input type=number name=height_cm required min=100 max=250 "
            "step=0.1></label>"
            "<label>Sex <select name=sex><option value=unknown>not given</option>"
            "<option value=female>female</option><option value=male>male</option></select>"
            "</label><label>Mass, kg (optional) <input type=number name=mass_kg min=25 "
            "max=300 step=0.1></label>" + _camera_choice(cameras) +
            "<p>Stand as the picture shows, on a plain floor, the whole body in the frame: "
            "the front in an A-pose, the side from the person's left or right with the "
            "arms hanging down. Fitted clothes, hair tied up.</p>"
            "<img src='/poses.png' alt='the two poses' style='max-width:100%;width:24em'>"
            "<div class=photos>" + _photo_box("front", "Front photo")
            + _photo_box("side", "Side photo") + "</div>"
            "<button class=go id=go disabled>Measure</button><p id=error class=bad></p>"
            "</form>")
    return page("Measure a person", body, _MEASURE_SCRIPT)


_FIT_SCRIPT = """
async function poll() {
  const got = await (await fetch('/api/fits/' + FIT)).json();
  const box = document.getElementById('progress');
  if (got.state === 'done' || got.state === 'failed') { location.reload(); return; }
  box.textContent = got.state === 'queued'
    ? `queued: ${got.ahead} fit(s) ahead, about ${Math.round(got.left_s)} s left`
    : `fitting the body to the photos: ${Math.round(got.elapsed_s)} s so far, about ` +
      `${Math.round(got.left_s)} s left`;
  setTimeout(poll, 1000);
}
poll();
"""


def _measurement_rows(record: FitRecord) -> str:
    rows = []
    for key, (name, label) in MEASUREMENTS.items():
        value = record.measurements.get(name)
        if value is None:
            continue
        rows.append(f"<tr><td>{key}</td><td>{_e(label)}</td>"
                    f"<td class=num data-measurement='{name}'>{value['value_mm'] / 10:.1f}</td>"
                    f"<td class=num>± {value['spread_mm'] / 10:.1f}</td></tr>")
    return ("<table><tr><th></th><th>measurement</th><th>cm</th><th>±</th></tr>"
            + "".join(rows) + "</table>")


def fit_page(record: FitRecord, photos: dict, camera: str | None) -> str:
    """A fit: its progress while queued or fitting (polled), its reasons when it failed,
    its report when done (``photos``: run.json's record of what was read of the photos;
    ``camera``: the registered camera's name, or None)."""
    title = f"{record.person}, {record.created}"
    given = (f"<p>Stature {record.height_cm:g} cm, sex {_e(record.sex)}"
             + (f", mass {record.mass_kg:g} kg" if record.mass_kg else "") + "</p>")
    if record.state in ("queued", "fitting"):
        return page(title, given + "<p id=progress>waiting for the fit...</p>",
                    f"const FIT = {record.fit_id};" + _FIT_SCRIPT)
    if record.state == "failed":
        return page(title, given + f"<p class=bad id=reason>{_e(record.reason)}</p>"
                    "<p><a href='/'>Measure again</a></p>")
    base = f"/fits/{record.fit_id}/files/"
    pictures = "".join(f"<figure><img src='{base}{name}' alt='{_e(label)}'>"
                       f"<figcaption>{_e(label)}</figcaption></figure>"
                       for name, label in PICTURES.items())
    downloads = " · ".join(f"<a href='{base}{name}' download>{_e(label)}</a>"
                           for name, label in RESULT_FILES.items())
    used = photos["camera"] if camera is None else f"{camera} (calibrated)"
    read = f"Camera: {used}; the side photo shows {side_text(photos)}."
    warnings = [*photos.get("check_warnings", ()), *filter(None, [photos.get("fit_warning")])]
    body = (given + f"<p>{_e(read)}</p>"
            + "".join(f"<p class=warn>{_e(line)}</p>" for line in warnings)
            + _measurement_rows(record) + f"<p>Fitted in {record.seconds or 0:.0f} s. "
            f"Download: {downloads}</p><div class=pictures>{pictures}</div>"
            f"<p><a href='/people/{_quote(record.person)}'>All fits of "
            f"{_e(record.person)}</a></p>")
    return page(title, body)


def _quote(person: str) -> str:
    return quote(person, safe="")


def people_page(people: list[tuple[str, int, str | None]], query: str) -> str:
    """The people measured, searchable by id or name."""
    rows = "".join(f"<tr><td><a href='/people/{_quote(p)}'>{_e(p)}</a></td>"
                   f"<td class=num>{n}</td><td>{_e(latest or '')}</td></tr>"
                   for p, n, latest in people)
    body = (f"<form method=get><label>Search by id or name <input type=text name=q "
            f"value='{_e(query)}'></label></form>"
            + (f"<table><tr><th>id or name</th><th>fits</th><th>last measured</th></tr>"
               f"{rows}</table>" if people else "<p>No one yet.</p>"))
    return page("People measured", body)


def person_page(person: str, fits: list[FitRecord]) -> str:
    """A person's fits over time, each measurement with its change since the fit before."""
    done = [f for f in fits if f.state == "done"]
    head = "".join(f"<th><a href='/fits/{f.fit_id}'>{_e(f.created)}</a></th>"
                   for f in done)
    rows = []
    for key, (name, label) in MEASUREMENTS.items():
        cells, before = [], None
        for f in done:
            value = f.measurements.get(name, {}).get("value_mm")
            if value is None:
                cells.append("<td></td>")
                continue
            change = "" if before is None else f" ({(value - before) / 10:+.1f})"
            cells.append(f"<td class=num>{value / 10:.1f}{change}</td>")
            before = value
        rows.append(f"<tr><td>{key}</td><td>{_e(label)}</td>{''.join(cells)}</tr>")
    others = "".join(f"<li><a href='/fits/{f.fit_id}'>{_e(f.created)}</a>: "
                     f"{_e(f.state)} {_e(f.reason)}</li>" for f in fits if f.state != "done")
    body = ("<p>Centimetres; in brackets, the change since the fit before.</p>"
            + (f"<table><tr><th></th><th>measurement</th>{head}</tr>{''.join(rows)}</table>"
               if done else "<p>No finished fit yet.</p>")
            + (f"<h2>Other fits</h2><ul>{others}</ul>" if others else ""))
    return page(person, body)


_CAMERAS_SCRIPT = """
document.getElementById('calibrate').addEventListener('submit', async (event) => {
  event.preventDefault();
  const box = document.getElementById('result');
  box.className = ''; box.textContent = 'calibrating...';
  const answer = await fetch('/api/cameras', {method: 'POST', body: new FormData(event.target)});
  const got = await answer.json();
  box.innerHTML = '';
  if (got.problems) {
    box.className = 'bad'; box.textContent = got.problems.join(' '); return;
  }
  const lines = [`registered ${got.name}: ${got.views}; RMS reprojection error ` +
                 `${got.rms_px} px; corners in ${Math.round(got.coverage * 100)} % of the frame`];
  for (const view of got.each) {
    lines.push(`${view.photo}: ${view.status}` +
               (view.error_px === null ? '' : `, ${view.error_px.toFixed(3)} px`));
  }
  for (const line of lines) {
    const p = document.createElement('p'); p.textContent = line; box.appendChild(p);
  }
});
"""


def cameras_page(cameras) -> str:
    """The registered cameras, and a form to calibrate one from board photos."""
    rows = "".join(f"<tr><td>{_e(row['name'])}</td><td class=num>{row['rms_px']:.3f}</td>"
                   f"<td>{_e(row['views'])}</td><td>{_e(row['created'])}"
                   f"</td></tr>" for row in cameras)
    body = ((f"<table><tr><th>camera</th><th>RMS px</th><th>views</th><th>calibrated</th></tr>"
             f"{rows}</table>" if cameras else "<p>No camera registered: fits use each "
             "photo's own focal length.</p>")
            + "<h2>Calibrate a camera</h2><p>Print a chessboard (<code>calib board</code>), "
            "and take 10-20 photos of it with the camera that will photograph people, from "
            "different angles and across the whole frame, at the camera's zoom.</p>"
            "<form id=calibrate><label>Name <input type=text name=name required "
            "maxlength=100></label><label>Board <input type=text name=board required "
            "value='chessboard:9x6'></label><label>Square side, mm <input type=number "
            "name=square_mm required min=1 step=0.1></label><label>Board photos <input "
            "type=file name=photos accept='image/*' multiple required></label>"
            "<button class=go>Calibrate</button></form><div id=result></div>")
    return page("Cameras", body, _CAMERAS_SCRIPT)

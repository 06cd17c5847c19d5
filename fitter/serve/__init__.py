"""`fitter serve`: the studio page, to photograph, check and measure people from a phone
on the studio's own computer (docs/serve.md).

``uploads`` (photos decoded and stored re-encoded), ``store`` (the people and their fits
in SQLite), ``queue`` (fits on worker processes), ``pages`` (the HTML) and ``app`` (the
Starlette routes).
"""

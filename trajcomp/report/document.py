"""A report: its JSON document, its figures (drawn only for HTML), its text summary, its files.

The JSON document follows the schema ``trajcomp-report/1`` shipped as
``trajcomp/report/schema.json``. Figures are callables that return an
SVG text or a matplotlib figure; they run only when the HTML page is
rendered, so a JSON-only run never draws (nor imports matplotlib). A report that summarises its
per-target data carries them as arrays, written beside the JSON as a NumPy
``.npz`` sidecar (named in the document's ``full_data.path``).
"""

import contextlib
import dataclasses
import io
import json
import zipfile
from importlib import resources
from pathlib import Path

import numpy as np

from trajcomp.support.atomic import FileSet
from trajcomp.support.plain_data import plain

SCHEMA = "trajcomp-report/1"


@dataclasses.dataclass(frozen=True)
class Figure:
    """One figure of the HTML page.

    Attributes
    ----------
    section : str
        Key of the page section it belongs to.
    title, caption : str
    draw : callable
        ``draw() -> str`` (an ``<svg>`` element) or ``matplotlib.figure.Figure``.
    """

    section: str
    title: str
    caption: str
    draw: object


@dataclasses.dataclass(frozen=True)
class Report:
    """A report document (JSON-ready dict, see the schema), its figures and its full per-target data.

    Attributes
    ----------
    doc : dict
    figures : tuple of Figure
    data : dict of str to callable, optional
        The sidecar arrays the document's ``full_data`` describes, each built
        when called (None: the document holds everything).
    """

    doc: dict
    figures: tuple = ()
    data: dict = None

    @property
    def passed(self):
        """False when the report has a verdict and it fails."""
        verdict = self.doc.get("verdict")
        return verdict is None or verdict["result"] == "pass"

    def json_text(self):
        """The JSON document, indented, ending in a newline."""
        return json.dumps(plain(self.doc, non_finite_as_none=True), indent=1, allow_nan=False) + "\n"

    def html_text(self):
        """The self-contained HTML page (figures embedded)."""
        from trajcomp.report.html import render

        return render(self)

    def write(self, path, *, json_only=False, protect=(), into=None):
        """Write ``PATH.json``, unless ``json_only`` ``PATH.html``, and the sidecar, all or none.

        ``PATH`` is ``path`` without a ``.json`` or ``.html`` suffix
        (``cell.report`` gives ``cell.report.json``). The sidecar
        ``PATH.targets.npz`` (only with `data`) is named in the written
        document's ``full_data.path``. None of them may be one of the
        files ``protect`` names (the run's inputs and outputs).
        With ``into`` (a `trajcomp.support.atomic.FileSet`) they are staged
        into that set, committed with its other files (the program the
        report is of).

        Returns
        -------
        list of Path
            The files written.
        """
        json_path, html_path, data_path = report_paths(path)
        report, sidecar = self, {}
        if self.data is not None:
            sidecar[data_path] = npz_bytes(self.data)
            report = dataclasses.replace(self, doc={**self.doc, "full_data": {**self.doc["full_data"],
                                                                              "path": data_path.name}})
        files = {json_path: report.json_text().encode("utf-8")}
        if not json_only:
            files[html_path] = report.html_text().encode("utf-8")
        files.update(sidecar)
        with FileSet() if into is None else contextlib.nullcontext(into) as outputs:
            outputs.stage(files, protect=protect, advice="give --report another name")
        return list(files)


def report_paths(path):
    """``(PATH.json, PATH.html, PATH.targets.npz)`` of a report written to ``path`` (`Report.write`), Paths."""
    path = Path(path)
    base = path.with_suffix("") if path.suffix.lower() in (".json", ".html") else path
    return tuple(base.with_name(base.name + suffix) for suffix in (".json", ".html", ".targets.npz"))


def schema():
    """The JSON Schema (dict) of the report documents."""
    return json.loads(resources.files("trajcomp.report").joinpath("schema.json").read_text(encoding="utf-8"))


def npz_bytes(arrays):
    """An uncompressed ``.npz`` (as `numpy.savez` writes it) of ``{name: callable returning an array}``.

    The arrays are built and written one at a time, so only the archive and
    one array are in memory at once.
    """
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED, allowZip64=True) as archive:
        for name, build in arrays.items():
            with archive.open(f"{name}.npy", "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(build()), allow_pickle=False)
    return buffer.getbuffer()

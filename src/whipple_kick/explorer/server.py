"""The explorer's web server (Tornado) and its console script ``whipple-kick-explorer``.

Why Tornado: the page needs a server that answers many requests while runs go on elsewhere, and nothing
more. Tornado is that and only that: one maintained package with no dependencies of its own and no
JavaScript of its own (the page's script is ours, :mod:`.page`, and loads nothing from the internet), its
own HTTP server (no ASGI server to add), and it is already installed with the ``test`` extra (Dask's
distributed scheduler runs on it). A dashboard framework (Panel/Bokeh, Dash) would bring its own figures
and tens of MB of JavaScript to draw what the project's figure modules already draw; the page shows their
PNGs.

Every run, overlay, stability sweep and animation goes to the sweeps' process pool (:mod:`.jobs`) and the
handler awaits it without holding the server's one thread, so one user's run never holds up another's
page. A request that fails gets one line in JSON (a user's mistake: the command line's message, beside its
field; anything else: "internal error" and the server's log), never a dead server.

Example
-------
Skipped as a doctest: it serves until Ctrl-C.

>>> main(["--port", "8050", "--study", "docs/uncertainty_study"])   # doctest: +SKIP
whipple-kick-explorer: serving on http://127.0.0.1:8050/ (Ctrl-C stops it)
"""
import asyncio
import concurrent.futures as cf
import contextlib
import io
import json
import logging
import pathlib
import re
import secrets
import shutil
import sys
import tempfile
import zipfile

from whipple_kick import cli
from whipple_kick.errors import InputError
from whipple_kick.simulate.scenario import SETTINGS
from whipple_kick.studies import stability

from . import form, jobs, page, study

#: The address the server listens on: this machine only.
HOST = "127.0.0.1"
#: The default port (``--port``; 0 picks a free one).
DEFAULT_PORT = 8050
#: Largest request body [bytes]: the form with a BicycleParameters file (a few kB).
MAX_BODY_BYTES = 4 * 1024 * 1024
#: Files the page may fetch from a run's, overlay's or stability's folder, with their types.
SERVED = {"response.png": "image/png", jobs.OVERLAY: "image/png", "stability.png": "image/png",
          jobs.ANIMATION: "image/gif"}
_TOKEN = re.compile(r"^[0-9a-f]{16}$")
log = logging.getLogger("whipple_kick.explorer")


class JobLost(RuntimeError):
    """The pool lost the request's job (a worker process died): one line for the page, status 503."""


class Explorer:
    """The server's state: its work folder, the folders it made (by token), the study, the pool's size, the
    stability sweep's speeds."""

    def __init__(self, workdir, study_folder=None, workers=None, speeds=None):
        self.workdir = pathlib.Path(workdir)
        self.speeds = speeds   # the stability sweep's speeds [m/s]
        self.study = study_folder
        self.workers = workers
        self.folders = {}   # token -> folder (a run's, an overlay's, a stability sweep's)

    def new_folder(self, kind, name):
        """A new folder ``<workdir>/<kind>/<token>/<name>`` and its token."""
        token = secrets.token_hex(8)
        folder = self.workdir / kind / token / name
        folder.mkdir(parents=True)
        self.folders[token] = folder
        return token, folder

    def folder(self, token):
        """The folder of ``token``; InputError for an unknown one."""
        if not _TOKEN.match(token or "") or token not in self.folders:
            raise InputError(f"no run {token!r} on this server (it restarted, or the address is wrong)")
        return self.folders[token]

    async def submit(self, function, *args):
        """Run ``function(*args)`` in the sweeps' pool and await it without blocking the server."""
        try:
            future = jobs.submit(function, *args, workers=self.workers)
            return await asyncio.wrap_future(future)
        except cf.process.BrokenProcessPool:
            jobs.discard_pool()   # the next request gets a fresh pool
            raise JobLost("a worker process died during the request (a fresh pool takes the next one); try again") \
                from None


def _app(explorer):
    """The Tornado application of ``explorer``."""
    import tornado.web

    class Handler(tornado.web.RequestHandler):
        """JSON replies; a failure is one line (:meth:`write_error`), never a traceback to the page."""

        def reply(self, data, status=200):
            self.set_status(status)
            self.set_header("Content-Type", "application/json")
            self.finish(json.dumps(data, allow_nan=False))

        def write_error(self, status_code, **kwargs):
            exc = kwargs.get("exc_info", (None, None, None))[1]
            self.reply({"error": f"{self._reason}" if exc is None else f"internal error: {type(exc).__name__}: "
                        f"{exc}"}, status_code)

        async def guarded(self, work):
            """Await ``work()``; a user's mistake or a failing job is a one-line JSON reply."""
            try:
                await work()
            except form.FormError as exc:
                self.reply({"errors": exc.errors}, 200)
            except InputError as exc:
                self.reply({"error": str(exc)}, 400)
            except JobLost as exc:
                log.warning("request %s: %s", self.request.uri, exc)
                self.reply({"error": str(exc)}, 503)
            except Exception as exc:
                log.exception("request %s failed", self.request.uri)
                self.reply({"error": f"internal error: {type(exc).__name__}: {exc}"}, 500)

        async def scenario(self):
            """The scenario of the posted form (its BicycleParameters file saved first), parsed in a thread."""
            values = {k: self.get_body_argument(k, "") for k in form.PAGE_FIELDS}
            bicycle_file = None
            uploaded = self.request.files.get("bicycle_file") or []
            if uploaded and uploaded[0]["filename"]:
                name = re.sub(r"[^A-Za-z0-9_.-]", "_", pathlib.PurePath(uploaded[0]["filename"]).name)
                if not name.endswith(".txt"):
                    raise form.FormError({"bicycle": f"bicycle file {name!r} must be a BicycleParameters "
                                                     "<Name>Benchmark.txt file"})
                _, folder = explorer.new_folder("uploads", "bicycle")
                bicycle_file = folder / name
                bicycle_file.write_bytes(uploaded[0]["body"])
            return await asyncio.get_running_loop().run_in_executor(None, form.parse, values, bicycle_file)

    class PageHandler(Handler):
        def get(self):
            self.set_header("Content-Type", "text/html; charset=utf-8")
            self.finish(page.render(form.fields(), explorer.study))

    class RunHandler(Handler):
        async def post(self):
            async def work():
                scenario = await self.scenario()
                token, folder = explorer.new_folder("runs", cli._default_out(scenario).name)
                outcome = await explorer.submit(jobs.run_into, scenario, folder)
                self.reply({"run": {**outcome, "id": token, "label": _label(scenario),
                                    "figure_url": f"/files/{token}/response.png" if outcome["figure"] else None,
                                    "download_url": f"/download/{token}"}})
            await self.guarded(work)

    class OverlayHandler(Handler):
        async def post(self):
            async def work():
                try:
                    asked = json.loads(self.request.body or b"{}")
                    ids, numbers = asked["ids"], asked.get("numbers") or list(range(1, len(asked["ids"]) + 1))
                except (ValueError, KeyError, TypeError, AttributeError):
                    raise InputError("the overlay needs a JSON body {\"ids\": [run ids], \"numbers\": [their numbers "
                                     "on the page]}") from None
                if not isinstance(ids, list) or not 2 <= len(ids) <= page.MAX_OVERLAID:
                    raise InputError(f"overlay 2 to {page.MAX_OVERLAID} runs, not {ids!r}")
                if not isinstance(numbers, list) or len(numbers) != len(ids) \
                        or not all(isinstance(n, int) and not isinstance(n, bool) for n in numbers):
                    raise InputError(f"the overlay's run numbers {numbers!r} must be one whole number per run")
                folders = [str(explorer.folder(str(i))) for i in ids]
                token, folder = explorer.new_folder("overlays", "compare")
                await explorer.submit(jobs.overlay, folders, numbers, folder / jobs.OVERLAY)
                self.reply({"url": f"/files/{token}/{jobs.OVERLAY}"})
            await self.guarded(work)

    class AnimateHandler(Handler):
        async def post(self, token):
            async def work():
                folder = explorer.folder(token)
                if not (folder / jobs.ANIMATION).exists():
                    await explorer.submit(jobs.animate_into, str(folder))
                self.reply({"url": f"/files/{token}/{jobs.ANIMATION}"})
            await self.guarded(work)

    class StabilityHandler(Handler):
        async def post(self):
            async def work():
                speeds = explorer.speeds
                scenario = form.stability_scenario(await self.scenario(), speeds[0])
                token, folder = explorer.new_folder("stability", cli._default_out(scenario, "stability").name)
                lines = await explorer.submit(jobs.stability_into, scenario, speeds, folder)
                self.reply({"lines": lines, "url": f"/files/{token}/stability.png"})
            await self.guarded(work)

    class PBestHandler(Handler):
        async def get(self):
            async def work():
                if explorer.study is None:
                    self.reply({"note": "No study was given (whipple-kick-explorer --study DIR).", "text": False})
                    return
                s = SETTINGS["fz_n"]
                text = self.get_query_argument("fz_n", "").strip()
                fz = s.none_means if not text else form._value("fz_n", text)
                rows = study.p_best(explorer.study, fz)
                if rows is None:
                    loads = ", ".join(f"{v:g}" for v in study.loads(explorer.study))
                    self.reply({"note": f"The study has no P(best) for {fz:g} N (its loads: {loads} N); no load is "
                                        "interpolated.", "text": False})
                    return
                self.reply({"note": f"At {fz:g} N, from {explorer.study} (the study's own settings, not the form's).",
                            "text": True, "rows": rows})
            await self.guarded(work)

    class FileHandler(Handler):
        def get(self, token, name):
            try:
                path = explorer.folder(token) / name
            except InputError as exc:
                self.reply({"error": str(exc)}, 404)
                return
            if name not in SERVED or not path.is_file():
                self.reply({"error": f"no file {name!r} in {token}"}, 404)
                return
            self.set_header("Content-Type", SERVED[name])
            self.set_header("Cache-Control", "no-store")
            self.finish(path.read_bytes())

    class DownloadHandler(Handler):
        async def get(self, token):
            try:
                folder = explorer.folder(token)
            except InputError as exc:
                self.reply({"error": str(exc)}, 404)
                return
            data = await asyncio.get_running_loop().run_in_executor(None, _zipped, folder)
            self.set_header("Content-Type", "application/zip")
            self.set_header("Content-Disposition", f'attachment; filename="{folder.name}.zip"')
            self.finish(data)

    class NotFound(Handler):
        def prepare(self):
            self.reply({"error": f"no page {self.request.path!r} here"}, 404)

    return tornado.web.Application([
        (r"/", PageHandler), (r"/run", RunHandler), (r"/overlay", OverlayHandler),
        (r"/animate/([^/]*)", AnimateHandler), (r"/stability", StabilityHandler), (r"/pbest", PBestHandler),
        (r"/files/([^/]*)/([^/]*)", FileHandler), (r"/download/([^/]*)", DownloadHandler),
    ], default_handler_class=NotFound)


def _zipped(folder):
    """The run folder as a zip file's bytes, its files under the folder's name (as ``simulate`` named it)."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in sorted(folder.iterdir()):
            if path.is_file() and not path.name.startswith("."):
                archive.write(path, f"{folder.name}/{path.name}")
    return buffer.getvalue()


def _label(scenario):
    """A run in a few words for the list of runs."""
    rear, front = scenario.pressures
    load = f"{scenario.fz_n:g} N" if scenario.fz_n is not None else "default load"
    kick = f"kick {scenario.kick_displacement * 1e3:g} mm {scenario.kick_direction} ({scenario.kick_profile})"
    return (f"{scenario.tyre} {rear:g}/{front:g} kPa, {load}, {scenario.speed:g} m/s, {scenario.controller}, "
            f"{scenario.rider_body} rider, {kick}")


def _parser():
    p = cli._OneLineParser(
        prog="whipple-kick-explorer",
        description="A local web page to run, watch and compare kick-plate runs: the scenario's main settings, "
                    "the response figures and animation, up to four runs overlaid, each run's folder to "
                    "download (the files simulate writes), the stability against speed and an uncertainty "
                    "study's P(best). Serves on 127.0.0.1 only; loads nothing from the internet.",
        epilog="Needs the app extra: pip install 'whipple_kick[app]'. See docs/explorer.md.")
    p.add_argument("--port", type=int, default=DEFAULT_PORT,
                   help=f"port on 127.0.0.1 (default {DEFAULT_PORT}; 0: a free one)")
    p.add_argument("--study", metavar="DIR",
                   help="an uncertainty study's folder (holding p_best.csv, as recommend-pressure --uncertain "
                        "--out DIR writes): the page shows its P(best) for the chosen load")
    p.add_argument("--workers", type=int, metavar="N",
                   help="worker processes of the pool runs go to (default: one per CPU core, as sweeps)")
    start, stop, step = stability.DEFAULT_SPEEDS
    p.add_argument("--speeds", default=f"{start:g}:{stop:g}:{step:g}", metavar="START:STOP:STEP",
                   help=f"speeds of the page's stability sweep in m/s, as stability --speeds: START:STOP:STEP (STOP "
                        f"included) or V1,V2,... (default {start:g}:{stop:g}:{step:g}, the stability command's)")
    p.add_argument("--workdir", metavar="DIR",
                   help="folder the runs are written into (default: a temporary folder, removed at exit)")
    return p


def _serve(argv):
    args = _parser().parse_args(argv)
    try:
        import tornado.httpserver
        import tornado.ioloop
        import tornado.netutil
    except ImportError:
        raise InputError("the explorer needs Tornado, in the app extra: pip install 'whipple_kick[app]'") from None
    if args.study is not None:
        study.check_folder(args.study)
    if args.workers is not None and args.workers < 1:
        raise InputError(f"--workers {args.workers} must be a whole number >= 1")
    speeds = stability.parse_speeds(args.speeds)
    if not 0 <= args.port <= 65535:
        raise InputError(f"--port {args.port} is outside the allowed range [0, 65535]")
    own = args.workdir is None
    workdir = pathlib.Path(tempfile.mkdtemp(prefix="whipple_kick_explorer_") if own else args.workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    logging.basicConfig(level=logging.WARNING, format="whipple-kick-explorer: %(message)s")
    try:
        explorer = Explorer(workdir, args.study, args.workers, speeds)
        jobs.start_pool(args.workers)   # forked before the server starts; the compiled model loaded once, here
        try:
            sockets = tornado.netutil.bind_sockets(args.port, HOST)
        except OSError as exc:
            raise InputError(f"--port {args.port} cannot be used on {HOST}: {exc.strerror or exc}") from None
        server = tornado.httpserver.HTTPServer(_app(explorer), max_body_size=MAX_BODY_BYTES)
        server.add_sockets(sockets)
        port = sockets[0].getsockname()[1]
        print(f"whipple-kick-explorer: serving on http://{HOST}:{port}/ (Ctrl-C stops it)", flush=True)
        tornado.ioloop.IOLoop.current().start()
    finally:
        if own:
            shutil.rmtree(workdir, ignore_errors=True)
        with contextlib.suppress(Exception):
            jobs.discard_pool(end_workers=True)   # no worker outlives the server
    return 0


def main(argv=None):
    """Console script ``whipple-kick-explorer`` (see ``whipple-kick-explorer --help``)."""
    sys.exit(cli._run(_serve, argv, "whipple-kick-explorer", kept="the server stopped"))


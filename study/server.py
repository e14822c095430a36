"""The participant's local web server (Starlette + uvicorn).

One server runs one participant's session.  Routes (nothing else answers; every
error is a JSON object ``{"error": "..."}`` with a 4xx status):

``GET  /``                  the page: the jsPsych site that ``export-web`` builds, in its
                            ``local`` host mode (:func:`flipstudy.study.web.site.site_files`)
``GET  /<file>``            the site's ``config.js``, scripts and CSS, and ``lib/<file>``
                            (jsPsych, from npm: :func:`flipstudy.study.web.jspsych.fetch`;
                            a 503 naming the problem when it cannot be had): a fixed set
                            held in memory, served by exact name
``GET  /api/session``       the timeline (:func:`flipstudy.study.timeline.build_timeline`)
``GET  /api/trial/<n>``     trial ``n``'s filled screen (:func:`flipstudy.study.timeline.trial_screen`
                            of ``session.resolve(n)``: an adaptive trial's level is chosen
                            here); only the current trial (the first unanswered) is served
``POST /api/answer``        one trial's answer (:func:`flipstudy.study.session.submit_answer`);
                            the reply is its ``status``, ``trial``, ``next_trial`` and ``finished``
``POST /api/demographics``  the demographics (:func:`flipstudy.study.session.submit_demographics`)
``GET  /stimuli/<name>.mp4`` a stimulus video: ``name`` must be the page's name of a
                            stimulus of the manifest and the file must resolve inside
                            ``STUDY_DIR/render/`` (no traversal, no symlinks out)

Conditions hidden from the participant: the page knows each stimulus by its opaque name
only (:class:`flipstudy.study.web.opaque.PageNames`, the exported site's names, from
``STUDY/web/site-map.json``), in its screens, video URLs, ``config.js`` and messages;
an answer's ``stimulus`` is that name, mapped back here, so the database stores the
study's own names.

Experimenter actions (export, status) are command-line only.  The server binds
to 127.0.0.1 unless told otherwise, accepts only loopback ``Host`` headers then
(on another address: the machine's names and addresses and ``--allowed-host``
names, never any name, against DNS rebinding), refuses cross-origin posts and
anything but ``application/json`` bodies of at most 8 KiB.  One server per
participant: :mod:`flipstudy.study.lock`.  It serves only videos that ``render.json``
says were made from the current stimuli with one set of settings.

Examples
--------
``serve`` runs until it is stopped (Ctrl-C), so it is not run here:

>>> serve("study/", "P01", open_browser=False)        # doctest: +SKIP
participant page: http://127.0.0.1:41233/

The same app in a background thread (:class:`ServerThread`) on a tiny study:

>>> import json, tempfile, pathlib, urllib.request
>>> from flipstudy.study.demo import make_demo_study
>>> tmp = tempfile.TemporaryDirectory()
>>> session = open_session(load_study(make_demo_study(pathlib.Path(tmp.name) / "study")), "P01")
>>> with ServerThread(create_app(session)) as srv:
...     timeline = json.load(urllib.request.urlopen(srv.url + "api/session"))
>>> timeline["participant"], timeline["n_trials"]
('P01', 8)
>>> tmp.cleanup()
"""
from __future__ import annotations

import ipaddress
import socket
import sys
import threading
import webbrowser
from pathlib import Path

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Route

from flipstudy.errors import JsPsychFetchError, RequestError, SessionError, StudyChangedError

from .session import Session, load_study, open_session, submit_answer, submit_demographics
from .timeline import build_timeline, is_default, trial_screen
from .validate import MAX_BODY, parse_json_object
from .web import jspsych as jsp
from .web.opaque import PageNames, hide_config
from .web.site import LOCAL, lib_files, site_config, site_csp, site_files

MEDIA_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
               ".css": "text/css; charset=utf-8"}
CSP = site_csp(LOCAL) + "; frame-ancestors 'none'"
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1", "[::1]")


def _error(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status, headers={"Cache-Control": "no-store"})


def is_loopback(host: str) -> bool:
    if host in ("localhost",):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def allowed_host_names(host: str, extra=()) -> set[str]:
    """The names a ``Host`` header may carry for a server listening on ``host``
    (DNS-rebinding guard): the loopback names, ``host`` itself, ``extra``
    (``--allowed-host``) and, for a non-loopback address, this machine's host
    name, its fully qualified name and the addresses that name resolves to
    (IPv6 ones also in brackets).  A wildcard (0.0.0.0, ::) is not a name a
    browser sends, so it is not added."""
    names = {n.lower() for n in LOOPBACK_NAMES}
    wildcard = host in ("0.0.0.0", "::", "")
    if not wildcard:
        names.add(host.lower())
    if not is_loopback(host):
        machine = {socket.gethostname()}
        try:
            machine.add(socket.getfqdn())
        except OSError:
            pass
        names |= {m.lower() for m in machine if m}
        for m in list(machine):
            try:
                for info in socket.getaddrinfo(m, None, type=socket.SOCK_STREAM):
                    names.add(info[4][0].lower())
            except OSError:
                pass
    for n in extra or ():
        n = str(n).strip().lower()
        if n:
            names.add(n)
    names |= {f"[{n}]" for n in list(names) if ":" in n and not n.startswith("[")}
    return names


class _Guard:
    """ASGI middleware: Host-header check (DNS rebinding) and security headers."""

    def __init__(self, app, allowed_hosts: set[str] | None):
        self.app, self.allowed = app, allowed_hosts

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        if self.allowed is not None:
            host = dict(scope["headers"]).get(b"host", b"").decode("latin-1")
            name = host.rsplit(":", 1)[0] if not host.endswith("]") else host
            if name.lower() not in self.allowed:
                resp = _error(400, f"host {host!r} is not served here")
                return await resp(scope, receive, send)

        async def send_with_headers(message):
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                headers += [(b"x-content-type-options", b"nosniff"),
                            (b"referrer-policy", b"no-referrer"),
                            (b"x-frame-options", b"DENY"),
                            (b"cross-origin-resource-policy", b"same-origin")]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, send_with_headers)


async def _read_json(request: Request) -> dict:
    ctype = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if ctype != "application/json":
        raise RequestError(415, "send the body as application/json")
    origin = request.headers.get("origin")
    if origin is not None and origin != f"{request.url.scheme}://{request.headers.get('host', '')}":
        raise RequestError(403, "cross-origin posts are refused")
    cl = request.headers.get("content-length")
    if cl is not None and (not cl.isdigit() or int(cl) > MAX_BODY):
        raise RequestError(413, f"request body too large (at most {MAX_BODY} bytes)")
    body = b""
    async for chunk in request.stream():
        body += chunk
        if len(body) > MAX_BODY:
            raise RequestError(413, f"request body too large (at most {MAX_BODY} bytes)")
    return parse_json_object(body)


#: HTTP status of every request once the study changed under the server (the page shows the message)
CHANGED_STATUS = 410


def _changed_message(e: StudyChangedError, stored_elsewhere: bool) -> str:
    return ("This session cannot record answers any more: the study was changed on the "
            "experimenter's computer" + (", so your last answer was NOT recorded" if stored_elsewhere
                                          else "") +
            ". Please tell the experimenter. (" + str(e) + ")")


def local_site(session: Session, *, iti_ms: int = 500, jspsych_dir=None, lib: bool = True,
               names: PageNames | None = None) -> dict[str, bytes]:
    """The files of the site ``export-web`` builds, in its ``local`` host mode, for
    ``session``'s study: ``{relative path: bytes}``, its videos by their opaque names
    (``names``; None: the study's, :class:`~flipstudy.study.web.opaque.PageNames`).
    jsPsych (``lib/``, left out with ``lib=False``) comes from ``jspsych_dir`` or npm's
    cache (:func:`flipstudy.study.web.jspsych.fetch`)."""
    folder = jsp.fetch(jspsych_dir)[0] if lib else None
    names = names or PageNames(session.study)
    cfg = site_config(session.study, host=LOCAL, iti_ms=iti_ms, n_trials=session.n_trials)
    return site_files(hide_config(cfg, names.map), folder)


#: what the page is told of a stored answer (not the next trial's stimulus, group or level)
ANSWER_REPLY = ("status", "trial", "next_trial", "finished")


def _answer_in_study_names(names: PageNames, obj: dict, session: Session | None = None) -> dict:
    """The page's answer with its ``stimulus`` (the page's name of a video) the study's;
    :class:`RequestError` (400) for a name the page was not given.  A 2AFC answer names
    its two videos in the order shown (``stimuli``): its ``stimulus`` is the one that
    is not the comparison, and that order must be the one the session stored for the
    trial (``first``; else 409)."""
    if isinstance(obj, dict) and "stimuli" in obj:
        got = names.pair(obj["stimuli"])
        if got is None:
            raise RequestError(400, "stimuli: not the page's names of a 2AFC trial's two videos")
        n = obj.get("trial")
        trials = session.trials if session is not None else []
        if isinstance(n, int) and 1 <= n <= len(trials) and trials[n - 1].first not in ("", got[1]):
            raise RequestError(409, f"trial {n}: its two videos were not shown in that order")
        obj = {k: v for k, v in obj.items() if k != "stimuli"}
        return dict(obj, stimulus=got[0])
    page_name = obj.get("stimulus")
    if not isinstance(page_name, str):
        return obj                                   # missing or not a string: refused as before
    real = names.stimulus(page_name)
    if real is None:
        raise RequestError(400, f"stimulus: {page_name[:40]!r} is not the name of a video of this page")
    return dict(obj, stimulus=real)


def _site_routes(files: dict[str, bytes], jspsych_dir):
    """The handlers of the page (``GET /``) and of the site's other files (``files``:
    :func:`local_site` without ``lib/``, whose files are read when first asked for)."""
    lib_lock = threading.Lock()

    def load_lib():
        with lib_lock:
            if not any(name.startswith("lib/") for name in files):
                files.update(lib_files(jsp.fetch(jspsych_dir)[0]))

    async def page(request: Request):
        return Response(files["index.html"], media_type=MEDIA_TYPES[".html"],
                        headers={"Content-Security-Policy": CSP, "Cache-Control": "no-store"})

    async def static(request: Request):
        name = request.path_params["name"]
        if request.url.path.startswith("/lib/"):
            name = f"lib/{name}"
            try:
                await run_in_threadpool(load_lib)
            except JsPsychFetchError as e:
                return _error(503, str(e))
        if name not in files or name == "index.html":     # only the site's own files, by exact name
            return _error(404, "not found")
        return Response(files[name], media_type=MEDIA_TYPES[name[name.rindex("."):]],
                        headers={"Cache-Control": "no-cache"})
    return page, static


def _video_route(study, names: PageNames):
    """The handler of ``GET /stimuli/<name>.mp4``: ``name`` is the page's name of a
    stimulus of the manifest (never the stimulus's own), its file inside ``render/``."""
    render_dir = study.render_dir.resolve()
    videos = {f"{names.video(r.stimulus)}.mp4": f"{r.stimulus}.mp4" for r in study.manifest}

    async def stimulus(request: Request):
        name = videos.get(request.path_params["name"])
        if name is None:                             # only the page's names of the manifest's stimuli
            return _error(404, "no such stimulus")
        path = (render_dir / name).resolve()
        if path.parent != render_dir or not path.is_file():   # symlinks out, directories
            return _error(404, "no such stimulus")
        return FileResponse(path, media_type="video/mp4", headers={"Cache-Control": "no-cache"})
    return stimulus


def _checked_submit(session: Session, submit, obj: dict):
    """``submit(session, obj)`` into the pinned study's own database only: checked before,
    and after (a :class:`StudyChangedError` then carries ``stored_elsewhere``)."""
    session.check_intact()                   # not into a database that is not the study's
    result = submit(session, obj)
    try:
        session.check_intact()               # committed into the study's own file?
    except StudyChangedError as e:
        e.stored_elsewhere = True
        raise
    return result


async def _http_error(request: Request, exc: HTTPException):
    msg = {404: "not found", 405: "method not allowed"}.get(exc.status_code, str(exc.detail))
    return _error(exc.status_code, msg)


async def _server_error(request: Request, exc: Exception):
    return _error(500, "internal error (see the terminal running flipstudy run)")


def create_app(session: Session, *, iti_ms: int = 500, allowed_hosts=("127.0.0.1", "localhost", "::1"),
               on_answer=None, on_changed=None, jspsych_dir=None, names: PageNames | None = None) -> Starlette:
    """The ASGI app serving ``session``.  ``allowed_hosts`` (Host header names; None =
    any) guards against DNS rebinding; ``on_answer(result)`` is called after every
    stored answer.  The page is :func:`local_site`; jsPsych's ``lib/`` files are read
    when first asked for (``jspsych_dir``: its npm packages; :func:`serve` fetches them).
    ``names``: the page's names of the stimuli (None: the study's opaque names,
    :class:`~flipstudy.study.web.opaque.PageNames`, kept in ``STUDY/web/site-map.json``).

    A pinned session (:meth:`Session.pin`) is checked before and after every
    answer: once its study folder, database, manifest or design changed, every
    API request is refused with status :data:`CHANGED_STATUS` and a message the
    page shows, and an answer committed to a database that is no longer the
    study's is never acknowledged as stored.  ``on_changed(message)`` is called
    the first time (the CLI prints it)."""
    told = []

    def changed(e: StudyChangedError, stored_elsewhere: bool = False) -> JSONResponse:
        if not told:
            told.append(True)
            if on_changed is not None:
                on_changed(str(e))
        return _error(CHANGED_STATUS, _changed_message(e, stored_elsewhere))
    study = session.study
    names = names or PageNames(study)
    page, static = _site_routes(local_site(session, iti_ms=iti_ms, lib=False, names=names), jspsych_dir)

    async def api_session(request: Request):
        try:
            session.check_intact()
        except StudyChangedError as e:
            return changed(e)
        tl = await run_in_threadpool(
            lambda: build_timeline(session, session.state(), iti_ms=iti_ms, name=names.video))
        return JSONResponse(tl, headers={"Cache-Control": "no-store"})

    tagged = not is_default(study.design)
    replay = bool(study.design.session.replay)

    def current_trial(n: int) -> dict:
        nxt = session.state()["next_trial"]
        if n != nxt:
            raise RequestError(409, f"trial {n} is not the current trial (the current one is "
                                    f"{nxt if nxt <= session.n_trials else 'none: the session is finished'})")
        return trial_screen(session.resolve(n), session.n_trials, replay=replay, iti_ms=iti_ms,
                            tagged=tagged, name=names.video)

    async def api_trial(request: Request):
        raw = request.path_params["n"]
        if not raw.isdigit() or not 1 <= int(raw) <= session.n_trials:
            return _error(404, f"no trial {raw[:20]!r} in this session (1 to {session.n_trials})")
        try:
            session.check_intact()
            screen = await run_in_threadpool(current_trial, int(raw))
        except RequestError as e:
            return _error(e.status, names.text(e.message))
        except StudyChangedError as e:
            return changed(e)
        return JSONResponse(screen, headers={"Cache-Control": "no-store"})

    async def _submit(request: Request, submit):
        """(result, None) of ``submit(session, JSON body)``, or (None, the error response)."""
        try:
            obj = await _read_json(request)
            return await run_in_threadpool(_checked_submit, session, submit, obj), None
        except RequestError as e:
            return None, _error(e.status, names.text(e.message))
        except StudyChangedError as e:
            return None, changed(e, getattr(e, "stored_elsewhere", False))

    async def api_answer(request: Request):
        result, err = await _submit(request, lambda s, obj: submit_answer(
            s, _answer_in_study_names(names, obj, s)))
        if err is not None:
            return err
        if on_answer is not None and result["status"] == "stored":
            on_answer(result)
        return JSONResponse({k: result[k] for k in ANSWER_REPLY}, headers={"Cache-Control": "no-store"})

    async def api_demographics(request: Request):
        result, err = await _submit(request, submit_demographics)
        return err if err is not None else JSONResponse(result, headers={"Cache-Control": "no-store"})

    stimulus = _video_route(study, names)

    app = Starlette(routes=[
        Route("/", page, methods=["GET"]),
        Route("/api/session", api_session, methods=["GET"]),
        Route("/api/trial/{n}", api_trial, methods=["GET"]),
        Route("/api/answer", api_answer, methods=["POST"]),
        Route("/api/demographics", api_demographics, methods=["POST"]),
        Route("/stimuli/{name:path}", stimulus, methods=["GET"]),
        Route("/favicon.ico", lambda request: Response(status_code=204), methods=["GET"]),
        Route("/lib/{name}", static, methods=["GET"]),
        Route("/{name}", static, methods=["GET"]),
    ], exception_handlers={HTTPException: _http_error, 500: _server_error})
    app.router.redirect_slashes = False
    hosts = None if allowed_hosts is None else {h.lower() for h in allowed_hosts} | {"[::1]"}
    app.add_middleware(_Guard, allowed_hosts=hosts)
    return app


def bind(host: str = "127.0.0.1", port: int = 0) -> socket.socket:
    """A listening TCP socket (port 0: a free one), SO_REUSEADDR so a restarted
    server gets its port back at once."""
    infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, proto=socket.IPPROTO_TCP)
    family, _, _, _, addr = infos[0]
    # proto=IPPROTO_TCP matters: asyncio sets TCP_NODELAY only on sockets that say so,
    # and without it every response waits ~40 ms for a delayed ACK (Nagle)
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(addr)
    except OSError as e:
        sock.close()
        raise SessionError(f"cannot listen on {host}:{port}: {e.strerror} (choose another --port, "
                           f"or leave it out for a free one)") from None
    sock.listen(128)
    sock.set_inheritable(True)
    return sock


def serve(study_dir, participant: str, *, host: str = "127.0.0.1", port: int = 0,
          open_browser: bool = True, new_session: bool = False, iti_ms: int = 500,
          allowed_hosts=(), out=sys.stdout) -> int:
    """Open or resume the session, print the URL, open the browser and serve
    until interrupted (Ctrl-C).  One server per participant: a second one for
    the same participant of the same study is refused (:mod:`flipstudy.study.lock`).
    ``allowed_hosts``: more names the Host header may carry (see
    :func:`allowed_host_names`)."""
    from .validate import check_participant
    try:
        check_participant(participant)
    except RequestError as e:
        raise SessionError(e.message) from None
    from .lock import ParticipantLock, StudyOpen
    if Path(study_dir).is_dir():
        held = StudyOpen(study_dir).acquire()     # no command replaces the study while it serves
    else:
        held = None
    try:
        study = load_study(study_dir)
        lock = ParticipantLock(study.dir, participant).acquire(host_arg=host)
        try:
            return _serve_locked(study, participant, lock, host=host, port=port,
                                 open_browser=open_browser, new_session=new_session, iti_ms=iti_ms,
                                 allowed_hosts=allowed_hosts, out=out)
        finally:
            lock.release()
    finally:
        if held is not None:
            held.release()


def _serve_locked(study, participant, lock, *, host, port, open_browser, new_session, iti_ms,
                  allowed_hosts, out) -> int:
    import uvicorn

    from flipstudy.errors import StaleRenderError
    from flipstudy.render.record import check_rendered
    open_session(study, participant, new_session=new_session, dry_run=True)   # refusals first
    missing = study.missing_videos()
    if missing:
        raise SessionError(f"{len(missing)} of {len(study.manifest)} stimulus videos are missing in "
                           f"{study.render_dir} (e.g. {missing[0]}.mp4); render them first: "
                           f"flipstudy render {study.dir}")
    try:       # every video made from the stimulus as it is now, all with one settings record
        check_rendered(study.stimuli, "video")
    except StaleRenderError as e:
        raise SessionError(str(e)) from None
    if lock.previous and lock.previous.get("pid"):
        print(f"flipstudy run: note: took over the lock of a server that is gone "
              f"(pid {lock.previous['pid']}, since {lock.previous.get('since', '?')})", file=out)
    jspsych_folder, _ = jsp.fetch()          # the page's jsPsych (npm's cache), before anyone waits
    names = PageNames(study)                 # the page's opaque names (STUDY/web/site-map.json)
    session = open_session(study, participant, new_session=new_session)
    session.pin()                    # answers go into this folder's database, or are refused
    state = session.state()
    sock = bind(host, port)
    port = sock.getsockname()[1]
    # a wildcard address is not one a browser can open: show this machine's loopback
    shown = {"0.0.0.0": "127.0.0.1", "::": "::1"}.get(host, host)
    url_host = f"[{shown}]" if ":" in shown else shown
    url = f"http://{url_host}:{port}/"
    loop = is_loopback(host)
    what = (f"resuming session {session.session} at trial {state['next_trial']} of {session.n_trials}"
            if session.resumed and not state["finished"] else
            f"session {session.session}, {session.n_trials} trials")
    print(f"flipstudy run: participant {participant}, {what}", file=out)
    if not loop:
        print(f"flipstudy run: warning: listening on {host}, reachable from the network", file=out)
    allowed = allowed_host_names(host, allowed_hosts)
    if not loop:
        print(f"flipstudy run: the page answers only to the Host names "
              f"{', '.join(sorted(n for n in allowed if not n.startswith('[')))} "
              f"(more with --allowed-host NAME)", file=out)
    print(f"participant page: {url}", file=out, flush=True)
    lock.update(url=url, port=port)

    def progress(result):
        msg = f"{participant}: {result['trial']}/{session.n_trials} answered"
        if result["finished"]:
            msg += " — session finished; press Ctrl-C to stop the server"
        print(msg, file=out, flush=True)

    def changed(message):
        print(f"flipstudy run: error: {message}; no more answers are taken: stop this server "
              f"(Ctrl-C) and start it again on the study as it is now", file=out, flush=True)

    app = create_app(session, iti_ms=iti_ms, allowed_hosts=allowed, on_answer=progress,
                     on_changed=changed, jspsych_dir=jspsych_folder, names=names)
    config = uvicorn.Config(app, log_level="warning", access_log=False, proxy_headers=False,
                            server_header=False, lifespan="off", timeout_graceful_shutdown=3)
    server = uvicorn.Server(config)
    if open_browser:
        threading.Timer(0.2, webbrowser.open, args=(url,)).start()
    try:
        server.run(sockets=[sock])
    finally:      # uvicorn re-raises Ctrl-C (KeyboardInterrupt) after its graceful shutdown
        s = session.state()
        print(f"flipstudy run: stopped; {participant} session {session.session}: "
              f"{s['answered']}/{session.n_trials} answered"
              + ("" if s["finished"] else " (run the same command to resume)"), file=out, flush=True)
    return 0


class ServerThread:
    """Serve an app on 127.0.0.1 in a background thread (tests, notebooks).

    >>> import tempfile, pathlib, urllib.request
    >>> from flipstudy.study.demo import make_demo_study
    >>> tmp = tempfile.TemporaryDirectory()
    >>> session = open_session(load_study(make_demo_study(pathlib.Path(tmp.name) / "study")), "P01")
    >>> with ServerThread(create_app(session)) as srv:
    ...     print(srv.url.startswith("http://127.0.0.1:"), urllib.request.urlopen(srv.url).status)
    True 200
    >>> tmp.cleanup()
    """

    def __init__(self, app, host: str = "127.0.0.1", port: int = 0):
        import uvicorn
        self.sock = bind(host, port)
        self.port = self.sock.getsockname()[1]
        self.url = f"http://{host}:{self.port}/"
        self.server = uvicorn.Server(uvicorn.Config(app, log_level="warning", access_log=False,
                                                    lifespan="off", proxy_headers=False))
        self.thread = threading.Thread(target=self.server.run, kwargs={"sockets": [self.sock]},
                                       daemon=True)

    def __enter__(self):
        import time
        self.thread.start()
        t0 = time.monotonic()
        while not self.server.started:
            if not self.thread.is_alive() or time.monotonic() - t0 > 20:
                raise RuntimeError("the server thread did not start")
            time.sleep(0.01)
        return self

    def __exit__(self, *exc):
        self.server.should_exit = True
        self.thread.join(timeout=10)
        self.sock.close()

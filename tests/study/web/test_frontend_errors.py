"""The one site in the local runner, when the server does not store an answer.

The server in front of the session answers ``POST /api/answer`` with an HTTP error and
a message (what a server whose study changed under it does): a 5xx is shown in the
banner and the answer is sent again until it is stored (once); a 4xx stops the page
with the server's message.  Neither ever moves on as if the answer were stored.
Headless Chromium (Debian's, through Playwright).
"""
import os

import pytest
from starlette.responses import JSONResponse

from test_session_browser import (APP, CHROMIUM, answer_trial, answers_in_db, do_intro,  # noqa: F401
                                  jspsych_dir, page, pw, screen, tiny, tiny_template)

from flipstudy.study.server import ServerThread, create_app
from flipstudy.study.session import load_study, open_session

pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason=f"needs Debian's chromium at {CHROMIUM} (apt-get install -y chromium)")


class Refusing:
    """The app, except that while ``fail`` is ``(status, message)`` every answer posted
    gets that error (and is not stored)."""

    def __init__(self, app):
        self.app, self.fail, self.refused = app, None, 0

    async def __call__(self, scope, receive, send):
        if (self.fail and scope["type"] == "http" and scope["method"] == "POST"
                and scope["path"] == "/api/answer"):
            self.refused += 1
            status, message = self.fail
            return await JSONResponse({"error": message}, status_code=status)(scope, receive, send)
        return await self.app(scope, receive, send)


@pytest.mark.slow
def test_a_server_error_is_shown_and_the_page_never_moves_on(page, tiny):  # noqa: F811
    session = open_session(load_study(tiny), "E01")
    app = Refusing(create_app(session, iti_ms=30))
    with ServerThread(app) as srv:
        page.goto(srv.url)
        do_intro(page)
        answer_trial(page, 1, "correct", "key")
        page.wait_for_selector(f'{APP}[data-stored="1"]')       # acknowledged by the server
        assert answers_in_db(tiny) == [(1, "correct")]

        # a 5xx: the message in the banner, the answer sent again until it is stored
        app.fail = (503, "the study folder changed under this server (design.toml)")
        answer_trial(page, 2, "incorrect", "click")
        page.wait_for_selector("#fs-banner:not([hidden])")
        assert "the study folder changed under this server" in page.inner_text("#fs-banner")
        assert page.get_attribute(APP, "data-screen-id") == "trial-2"
        assert answers_in_db(tiny) == [(1, "correct")]
        app.fail = None
        page.wait_for_selector(f'{APP}[data-stored="2"]')       # stored, then on
        page.wait_for_selector("#fs-banner[hidden]", state="attached")
        assert answers_in_db(tiny) == [(1, "correct"), (2, "incorrect")]

        # a 4xx: the page stops with the server's message; nothing more is stored
        app.fail = (409, "this session's study changed; ask the experimenter to restart flipstudy run")
        answer_trial(page, 3, "correct", "key")
        screen(page, "error")
        text = page.inner_text(APP)
        assert "ask the experimenter to restart flipstudy run" in text and "Your saved answers are safe" in text
        assert app.refused >= 2 and answers_in_db(tiny) == [(1, "correct"), (2, "incorrect")]
        assert page.query_selector("button.fs-correct") is None      # no trial 4 to answer
    session.close()

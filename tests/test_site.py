"""The reading edition as a reader sees it: the built site opened in headless Chromium.

Needs a built site (``python docs/build.py``, or ``VO_NOTEBOOKS_SITE`` naming another built
``html`` folder) and Debian's Chromium at /usr/bin/chromium, driven by Playwright without a
browser of its own; it skips saying which is missing, and never builds the site itself. The site
is served over http://127.0.0.1 from a thread (MathJax is part of the site: nothing may be fetched
from elsewhere), and a full-page screenshot of every page goes to ``screenshots/`` in the build
folder, beside ``html/``.
"""

from __future__ import annotations

import functools
import http.server
import os
import pathlib
import re
import shutil
import threading
from html import unescape

import pytest
from conftest import CHROMIUM, CHROMIUM_FLAGS

ROOT = pathlib.Path(__file__).resolve().parents[1]
SITE = pathlib.Path(os.environ.get("VO_NOTEBOOKS_SITE", ROOT / "docs" / "_build" / "html"))
LANDING = "index.html"
# Two notebook pages with figures, maths typeset from Markdown and sympy output, and widgets.
NOTEBOOK_PAGES = ["notebooks/01_crawler_odometry.html", "notebooks/02_circular_motion_derivation.html"]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
PAGE_TIMEOUT_MS = 60_000
VIEWPORT = {"width": 1280, "height": 900}

pytestmark = [
    pytest.mark.skipif(
        not CHROMIUM.is_file(), reason=f"no Chromium at {CHROMIUM} (apt-get install chromium)"
    ),
    pytest.mark.skipif(
        not (SITE / LANDING).is_file(),
        reason=f"site not built at {SITE}: run python docs/build.py (or set VO_NOTEBOOKS_SITE)",
    ),
]


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format, *args):  # noqa: A002 - the base class's signature
        pass


@pytest.fixture(scope="module")
def base_url():
    handler = functools.partial(QuietHandler, directory=str(SITE))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")
    profile = tmp_path_factory.mktemp("chromium-profile")  # a fresh --user-data-dir
    with sync_api.sync_playwright() as playwright:
        context = playwright.chromium.launch_persistent_context(
            str(profile),
            executable_path=str(CHROMIUM),
            args=CHROMIUM_FLAGS,
            headless=True,
            viewport=VIEWPORT,
        )
        try:
            yield context
        finally:
            context.close()


@pytest.fixture(scope="module")
def screenshots():
    folder = SITE.parent / "screenshots"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    return folder


def open_page(browser, base_url, path, screenshots):
    """Load ``path`` and let MathJax finish; return the page and every URL it requested."""
    page = browser.new_page()
    requested = []
    page.on("request", lambda request: requested.append(request.url))
    response = page.goto(base_url + path, wait_until="load", timeout=PAGE_TIMEOUT_MS)
    assert response is not None and response.ok, (path, response and response.status)
    page.wait_for_function(
        "() => !window.MathJax || (MathJax.startup && MathJax.startup.promise)", timeout=PAGE_TIMEOUT_MS
    )
    page.evaluate("() => window.MathJax ? MathJax.startup.promise.then(() => true) : true")
    page.screenshot(
        path=str(screenshots / (path.replace("/", "_").removesuffix(".html") + ".png")), full_page=True
    )
    return page, requested


def assert_reads_well(page, requested, base_url):
    """What every page must show: its images, no traceback, no raw widget, nothing from outside."""
    images = page.evaluate(
        "() => Array.from(document.images).map(i => [i.getAttribute('src'), i.complete, i.naturalWidth])"
    )
    broken = [src for src, complete, width in images if not (complete and width > 0)]
    assert not broken, f"images that did not load: {broken}"
    text = page.inner_text("body")
    assert "Traceback (most recent call last)" not in text
    assert page.locator(".traceback, .output.error").count() == 0
    assert "interactive(children=" not in text, "a widget shown as its text representation"
    outside = [url for url in requested if not url.startswith((base_url, "data:"))]
    assert not outside, f"requests that leave the site: {outside}"
    return images


def test_landing_page_is_the_readme_with_the_notebook_map(browser, base_url, screenshots):
    page, requested = open_page(browser, base_url, LANDING, screenshots)
    assert_reads_well(page, requested, base_url)
    assert page.locator("h1").first.inner_text().startswith("vo-notebooks")
    # The notebook map: one link per notebook, each to its page, and each page in the navigation.
    article_links = page.eval_on_selector_all(
        "article a.reference.internal", "links => links.map(a => a.getAttribute('href'))"
    )
    nav_links = page.eval_on_selector_all(
        "nav a.reference.internal", "links => links.map(a => a.getAttribute('href'))"
    )
    for nb in NOTEBOOKS:
        target = f"notebooks/{nb.stem}.html"
        assert target in article_links, f"the notebook map does not link {target}"
        assert target in nav_links, f"the navigation does not list {target}"
    for target in ("docs/errata.html", "docs/benchmarks.html"):
        assert target in nav_links, f"the navigation does not list {target}"
    page.close()


@pytest.mark.parametrize("path", NOTEBOOK_PAGES)
def test_notebook_page_shows_figures_maths_and_outputs(browser, base_url, screenshots, path):
    page, requested = open_page(browser, base_url, path, screenshots)
    images = assert_reads_well(page, requested, base_url)
    assert len(images) >= 1, f"{path}: expected its figures, found none"
    typeset = page.locator("mjx-container").count()
    assert typeset >= 3, f"{path}: MathJax typeset {typeset} formulas"
    assert page.locator("mjx-merror").count() == 0, f"{path}: a formula MathJax could not parse"
    outputs = page.locator(".cell_output").count()
    assert outputs >= 3, f"{path}: {outputs} cell outputs"
    stem = re.sub(r"\.html$", "", path.rsplit("/", 1)[-1])
    assert stem[:2] in page.locator("h1").first.inner_text()
    page.close()


@pytest.mark.parametrize(
    "path",
    [
        "docs/benchmarks.html",
        "docs/command_line.html",
        "docs/outputs.html",
        "docs/course.html",
        "docs/errata.html",
        "data/README.html",
        *(f"notebooks/{nb.stem}.html" for nb in NOTEBOOKS),
    ],
)
def test_every_page_reads_well(browser, base_url, path):
    """Every other page too: images loaded, maths parsed, no traceback, nothing from outside."""
    page = browser.new_page()
    requested = []
    page.on("request", lambda request: requested.append(request.url))
    response = page.goto(base_url + path, wait_until="load", timeout=PAGE_TIMEOUT_MS)
    assert response is not None and response.ok, (path, response and response.status)
    page.evaluate("() => window.MathJax ? MathJax.startup.promise.then(() => true) : true")
    assert_reads_well(page, requested, base_url)
    assert page.locator("mjx-merror").count() == 0, f"{path}: a formula MathJax could not parse"
    page.close()


def test_every_link_of_the_checked_pages_resolves(browser, base_url):
    """Internal links of the landing page and both notebook pages answer 200 (no broken link)."""
    request = browser.request
    checked = set()
    for path in [LANDING, *NOTEBOOK_PAGES]:
        page = browser.new_page()
        page.goto(base_url + path, wait_until="load", timeout=PAGE_TIMEOUT_MS)
        hrefs = page.eval_on_selector_all("a[href]", "links => links.map(a => a.href)")
        page.close()
        for href in hrefs:
            url = href.split("#", 1)[0]
            if url.startswith(base_url) and url not in checked:
                checked.add(url)
                assert request.get(url).ok, f"{path} links {url}, which does not load"
    assert len(checked) > len(NOTEBOOKS)


# The editions hold no answers: the public site folds solutions but shows no hidden test and no
# mark scheme; the student site (VO_NOTEBOOKS_STUDENT_SITE: docs/build.py --student --notebooks
# student) shows no solution line either. Read from the page as Chromium has it, folded parts too.
STUDENT_SITE = os.environ.get("VO_NOTEBOOKS_STUDENT_SITE")
HIDDEN_REGION = re.compile(r"^\s*### BEGIN HIDDEN TESTS\s*$(.*?)^\s*### END HIDDEN TESTS\s*$", re.M | re.S)
SOLUTION_REGION = re.compile(r"^\s*### BEGIN SOLUTION\s*$(.*?)^\s*### END SOLUTION\s*$", re.M | re.S)
MARKERS = ("BEGIN SOLUTION", "HIDDEN TESTS", "MARK SCHEME")


def secret_lines(path, solutions):
    """Stripped lines of the hidden tests and mark schemes (and of the solutions, if asked) of a
    notebook that the rest of the notebook does not also contain."""
    import jupytext

    cells = jupytext.read(path).cells
    secret = []
    for cell in cells:
        if cell.cell_type == "markdown" and cell.metadata.get("nbgrader", {}).get("solution"):
            secret.append(cell.source)
        secret += [m.group(1) for m in HIDDEN_REGION.finditer(cell.source)]
        if solutions:
            secret += [m.group(1) for m in SOLUTION_REGION.finditer(cell.source)]
    visible = "\n".join(c.source for c in cells)
    for text in secret:
        visible = visible.replace(text, "\n")
    elsewhere = {line.strip() for line in visible.splitlines()}
    return {line.strip() for t in secret for line in t.splitlines() if len(line.strip()) > 12} - elsewhere


def shown_lines(browser, url):
    """Every line of text of the page, its folded parts included."""
    page = browser.new_page()
    try:
        response = page.goto(url, wait_until="load", timeout=PAGE_TIMEOUT_MS)
        assert response is not None and response.ok, url
        html = page.content()
    finally:
        page.close()
    return {line.strip() for line in unescape(re.sub(r"<[^>]+>", "\n", html)).splitlines()}


def serve(folder):
    handler = functools.partial(QuietHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}/"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_public_site_shows_no_hidden_test_or_mark_scheme(browser, base_url, path):
    shown = shown_lines(browser, f"{base_url}notebooks/{path.stem}.html")
    assert not any(marker in line for line in shown for marker in MARKERS)
    assert sorted(secret_lines(path, solutions=False) & shown) == []


@pytest.mark.skipif(not STUDENT_SITE, reason="no student site named by VO_NOTEBOOKS_STUDENT_SITE")
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_student_site_shows_no_solution_hidden_test_or_mark_scheme(browser, path):
    server, url = serve(STUDENT_SITE)
    try:
        shown = shown_lines(browser, f"{url}notebooks/{path.stem}.html")
    finally:
        server.shutdown()
        server.server_close()
    assert not any(marker in line for line in shown for marker in MARKERS)
    assert sorted(secret_lines(path, solutions=True) & shown) == []

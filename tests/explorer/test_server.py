"""The explorer's server over HTTP (no browser): it never dies on a request, and a run does not hold up a page."""
import io
import json
import os
import pathlib
import re
import signal
import threading
import time
import urllib.error
import urllib.request
import uuid

import pytest


def _request(url, data=None, headers=None, timeout=120):
    """(status, body) of a request; an HTTP error status is an answer too."""
    req = urllib.request.Request(url, data=data, headers=headers or {})   # noqa: S310 -- the test's own server
    try:
        with urllib.request.urlopen(req, timeout=timeout) as response:   # noqa: S310 -- http://127.0.0.1 only
            return response.status, response.read()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read()


def _multipart(fields, files=()):
    """A multipart/form-data body and its header, as a browser sends a form."""
    boundary = uuid.uuid4().hex
    out = io.BytesIO()
    for name, value in fields.items():
        out.write(f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n{value}\r\n'.encode())
    for name, filename, body in files:
        out.write(f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"; filename="{filename}"\r\n'
                  "Content-Type: text/plain\r\n\r\n".encode() + body + b"\r\n")
    out.write(f"--{boundary}--\r\n".encode())
    return out.getvalue(), {"Content-Type": f"multipart/form-data; boundary={boundary}"}


@pytest.mark.parametrize("path, data, status", [
    ("nothing/here", None, 404),
    ("files/0123456789abcdef/response.png", None, 404),     # a run this server never made
    ("files/../../etc/passwd", None, 404),
    ("download/not-a-token", None, 404),
    ("overlay", b"not json", 400),
    ("overlay", json.dumps({"ids": ["0123456789abcdef", "fedcba9876543210"]}).encode(), 400),
    ("overlay", json.dumps({"ids": list("abcdefgh")}).encode(), 400),     # more than four
    ("overlay", json.dumps({"ids": ["0123456789abcdef"] * 2, "numbers": ["one", 2]}).encode(), 400),
    ("overlay", b"[1, 2]", 400),
    ("animate/0123456789abcdef", b"", 400),
    ("pbest?fz_n=heavy", None, 400),
    ("run", None, 405),                                     # a GET where a POST is expected
])
def test_a_bad_request_gets_one_line_and_the_server_serves_on(server, path, data, status):
    code, body = _request(server + path, data)
    assert code == status
    if code != 405:
        reply = json.loads(body)
        assert list(reply) == ["error"] and "\n" not in reply["error"]
    assert _request(server)[0] == 200


def test_a_refused_form_and_a_wrong_bicycle_file_are_one_line_beside_the_field(server):
    body, headers = _multipart({"pressure_kpa": "1e400", "fz_n": "10"})
    reply = json.loads(_request(server + "run", body, headers)[1])
    assert reply == {"errors": {"pressure_kpa": "'1e400' is not a finite number (kPa)"}}
    body, headers = _multipart({}, [("bicycle_file", "bike.exe", b"MZ")])
    assert "must be a BicycleParameters" in json.loads(_request(server + "run", body, headers)[1])["errors"]["bicycle"]
    body, headers = _multipart({}, [("bicycle_file", "BrokenBenchmark.txt", b"not = a bicycle\n")])
    errors = json.loads(_request(server + "run", body, headers)[1])["errors"]
    assert len(errors) == 1 and "\n" not in next(iter(errors.values()))


def test_a_run_in_progress_does_not_hold_up_another_page(server):
    """A 30 s run (a few seconds in its worker) is in flight while the page and the P(best) come back at once."""
    body, headers = _multipart({"duration": "30"})
    reply = {}
    thread = threading.Thread(target=lambda: reply.update(json.loads(_request(server + "run", body, headers)[1])))
    thread.start()
    time.sleep(0.3)
    started = time.perf_counter()
    page, pbest = _request(server), _request(server + "pbest?fz_n=701")
    waited = time.perf_counter() - started
    still_running = thread.is_alive()
    thread.join(timeout=120)
    assert page[0] == 200 and json.loads(pbest[1])["rows"]["settling"][0]["pressure"] == "300 kPa"
    # A server that a run blocked would answer the page only after the run's reply.
    assert still_running, "the page came back only after the run ended: blocked, or a run too short to tell"
    assert waited < 2.0, waited   # a page is a few ms, also on a loaded machine; the run takes seconds
    assert reply["run"]["outcome"] == "completed"


def _children(pid):
    """Process ids whose parent is ``pid`` (Linux: /proc)."""
    out = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:   # the process ended meanwhile
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


@pytest.mark.skipif(not pathlib.Path("/proc/self/stat").exists(), reason="finds the pool's workers in /proc (Linux)")
def test_a_worker_that_dies_costs_its_request_one_line_and_the_next_run_works(server):
    body, headers = _multipart({"duration": "30"})
    reply = {}
    thread = threading.Thread(target=lambda: reply.update(
        dict(zip(("status", "body"), _request(server + "run", body, headers), strict=True))))
    thread.start()
    time.sleep(0.5)
    workers = _children(server.pid)
    assert len(workers) == 2, workers     # the pool of --workers 2, started with the server
    for pid in workers:
        os.kill(pid, signal.SIGKILL)
    thread.join(timeout=120)
    assert reply["status"] == 503
    assert json.loads(reply["body"]) == {"error": "a worker process died during the request (a fresh pool takes "
                                                  "the next one); try again"}
    body, headers = _multipart({"duration": "1"})
    assert json.loads(_request(server + "run", body, headers)[1])["run"]["outcome"] == "completed"


def test_a_bicycleparameters_file_sent_with_the_form_is_the_bicycle(server):
    """BicycleParameters' own BrowserBenchmark.txt (its app data), sent as the page's file field, runs as
    ``simulate --bicycle BrowserBenchmark.txt`` would: its summary names the file's bicycle."""
    bp = pytest.importorskip("bicycleparameters", reason="the test extra's BicycleParameters ships the file")
    path = pathlib.Path(bp.__file__).parent / "app-data" / "bicycles" / "Browser" / "Parameters" / "BrowserBenchmark.txt"
    if not path.is_file():
        pytest.skip(f"this BicycleParameters has no {path.name} in its app data")
    body, headers = _multipart({"duration": "1"}, [("bicycle_file", path.name, path.read_bytes())])
    reply = json.loads(_request(server + "run", body, headers)[1])
    assert reply["run"]["outcome"] == "completed", reply
    assert reply["run"]["label"].startswith("T03 400/400 kPa")
    status, data = _request(server + reply["run"]["download_url"].lstrip("/"))
    import zipfile
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        summary = json.loads(next(archive.read(n) for n in archive.namelist() if n.endswith("summary.json")))
    assert status == 200 and summary["scenario"]["bicycle"].endswith("BrowserBenchmark.txt")


def test_stability_against_speed_is_the_stability_commands(server, tmp_path, capsys):
    """The page's stability of the form's setup prints what ``stability`` prints for the same flags and speeds."""
    from tests.conftest import STABILITY_SPEEDS, run_console
    from whipple_kick import cli

    body, headers = _multipart({"pressure_kpa": "300", "fz_n": "701", "speed": "4", "kick_direction": "left"})
    reply = json.loads(_request(server + "stability", body, headers)[1])
    status, out, _ = run_console(cli.stability_main, ["--pressure", "300", "--fz", "701", "--speeds", STABILITY_SPEEDS,
                                                      "--out", str(tmp_path / "st")], capsys)
    assert status == 0
    printed = out.splitlines()
    assert printed[0].startswith(f"stability: {reply['lines'][0]}; 4 speeds 2-5 m/s")
    assert printed[1:-1] == reply["lines"][1:]
    assert _request(server + reply["url"].lstrip("/"))[0] == 200


def test_the_page_loads_nothing_from_elsewhere(server):
    """No address outside the server: no CDN script, style, font or image (the page works offline)."""
    status, body = _request(server)
    text = body.decode()
    assert status == 200 and "http:" not in text and "https:" not in text
    addresses = re.findall(r'(?:src|href|action)="([^"]*)"', text)
    assert addresses and all(a.startswith(("/", "data:")) for a in addresses), addresses
    assert "fetch('/run'" in text or "post('/run'" in text   # the script talks to this server only

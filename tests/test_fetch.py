"""nfdepth.fetch and ``nfdepth fetch-data``, offline: downloads come from a local HTTP server.

No test reaches the internet: every URL fetched is ``http://127.0.0.1:<port>``
(a mirror serving the shared data folder or a temporary folder), and name
resolution of any other host fails (the ``offline`` fixture).
"""

from __future__ import annotations

import contextlib
import functools
import http.server
import re
import socket
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from cli_runner import run_cli

import nfdepth
from nfdepth import datasets as D
from nfdepth import fetch as F



def _shared_data() -> Path | None:
    from nfdepth.datasets import DataNotFoundError, data_root

    try:
        folder = data_root()
    except DataNotFoundError:
        return None
    if all((folder / name / "SHA256SUMS").is_file() and (folder / name / "SOURCE.md").is_file() for name in F.DATA_SETS):
        return folder
    return None


@pytest.fixture
def shared():
    folder = _shared_data()
    if folder is None:
        pytest.skip("the shared data folder (with SOURCE.md and SHA256SUMS per set) was not found: set NFDEPTH_DATA or put it at ../shared/data")
    return folder


@pytest.fixture(autouse=True)
def offline(monkeypatch):
    """Refuse to resolve any host but the loopback one, and bypass proxies for it."""
    real = socket.getaddrinfo

    def local_only(host, *args, **kwargs):
        if host not in ("127.0.0.1", "localhost", b"127.0.0.1", b"localhost"):
            raise socket.gaierror(f"test_fetch is offline: refusing to resolve {host!r}")
        return real(host, *args, **kwargs)

    monkeypatch.setattr(socket, "getaddrinfo", local_only)
    monkeypatch.setenv("NO_PROXY", "127.0.0.1,localhost")
    monkeypatch.setenv("no_proxy", "127.0.0.1,localhost")


class _Handler(http.server.SimpleHTTPRequestHandler):
    def __init__(self, *args, seen, **kwargs):
        self._seen = seen
        super().__init__(*args, **kwargs)

    def do_GET(self):
        self._seen.append(self.path)
        super().do_GET()

    def log_message(self, *args):  # keep the test output quiet
        pass


@contextlib.contextmanager
def serve(folder: Path):
    """Serve ``folder`` on 127.0.0.1; yields (base URL, list of the paths requested)."""
    seen: list = []
    handler = functools.partial(_Handler, seen=seen, directory=str(folder))
    server = http.server.HTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}", seen
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


def _closed_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


# ------------------------------------------------------------------ registry


def test_registry_equals_the_shared_sha256sums(shared):
    for name in F.DATA_SETS:
        listed = [line.split(None, 1) for line in (shared / name / "SHA256SUMS").read_text().splitlines() if line.strip()]
        entries = F.data_files(name)
        assert [(e.sha256, e.path) for e in entries] == [(h, p.strip()) for h, p in listed], name
        for e in entries:
            assert (shared / name / e.path).stat().st_size == e.size, e


def test_every_url_is_https_and_pinned():
    entries = F.data_files()
    assert {n: sum(e.dataset == n for e in entries) for n in F.DATA_SETS} == {
        "tsukuba": 6, "middlebury2003-teddy": 11, "middlebury2005": 50, "skimage-motorcycle": 3,
    }
    pinned = re.compile(
        r"^https://(raw\.githubusercontent\.com/[\w.-]+/[\w.-]+/[0-9a-f]{40}/"
        r"|github\.com/scikit-image/scikit-image/raw/v\d+\.\d+\.\d+/skimage/data/)"
    )
    for e in entries:
        assert pinned.match(e.url), e.url
        assert e.url.endswith("/" + e.path.rsplit("/", 1)[-1]), e.url
        assert re.fullmatch(r"[0-9a-f]{64}", e.sha256) and e.size > 0
    assert len({e.url for e in entries}) == len(entries)
    urls = {f"{e.dataset}/{e.path}": e.url for e in entries}
    assert urls["tsukuba/scene1.row3.col1.ppm"] == (
        "https://raw.githubusercontent.com/PaleCosmos/Multimedia_Lab/601fe2e7c85bac98def8c6038a404af6b40bae86/image/tsukuba/scene1.row3.col1.ppm"
    )
    assert urls["middlebury2003-teddy/im0.png"] == (
        "https://raw.githubusercontent.com/norishigefukushima/ViewSynthesis/d503b7822e655103c50a74f27c02ea4a4adbe6e1/ViewSynthesis/img/stereo/teddy/backup/im0.png"
    )
    assert urls["middlebury2003-teddy/disp2.pgm"] == (
        "https://raw.githubusercontent.com/xland16/disparitymapping/de5c48ec8f9e5893f324d9068372bd1a7c16b46c/teddy/disp2.pgm"
    )
    assert urls["middlebury2005/Reindeer/dmin.txt"] == (
        "https://raw.githubusercontent.com/norishigefukushima/ViewSynthesis/d503b7822e655103c50a74f27c02ea4a4adbe6e1/ViewSynthesis/img/stereo/Reindeer/dmin.txt"
    )
    assert urls["skimage-motorcycle/motorcycle_disp.npz"] == "https://github.com/scikit-image/scikit-image/raw/v0.25.2/skimage/data/motorcycle_disp.npz"


def test_mirror_urls_follow_the_data_layout():
    entries = F.data_files(["middlebury2005", "tsukuba"], mirror="http://lab.example.org/nfdepth/")
    assert entries[0].url == "http://lab.example.org/nfdepth/tsukuba/scene1.row3.col1.ppm"
    assert entries[-1].url == "http://lab.example.org/nfdepth/middlebury2005/Reindeer/view6.png"


def test_bad_arguments_are_refused_before_any_download(tmp_path):
    with pytest.raises(ValueError, match="sets must be among tsukuba, middlebury2003-teddy, .*got 'teddy'"):
        F.fetch_data(tmp_path, sets=["teddy"])
    with pytest.raises(ValueError, match="at least one"):
        F.fetch_data(tmp_path, sets=[])
    with pytest.raises(ValueError, match="mirror must be an http://, https:// or ftp:// URL"):
        F.fetch_data(tmp_path, mirror="lab.example.org/data")
    with pytest.raises(TypeError, match="dest must be a folder path"):
        F.fetch_data(3)
    (tmp_path / "file").write_text("x")
    with pytest.raises(NotADirectoryError, match="is not a folder"):
        F.fetch_data(tmp_path / "file", sets="tsukuba")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_default_data_dir(monkeypatch, tmp_path):
    monkeypatch.setattr(sys, "platform", "linux")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert F.default_data_dir() == tmp_path / "nfdepth" / "data"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/ignored")
    assert F.default_data_dir() == Path.home() / ".cache" / "nfdepth" / "data"
    monkeypatch.setattr(sys, "platform", "darwin")
    assert F.default_data_dir() == Path.home() / "Library" / "Caches" / "nfdepth" / "data"
    monkeypatch.setattr(sys, "platform", "win32")
    monkeypatch.setenv("LOCALAPPDATA", str(tmp_path / "Local"))
    assert F.default_data_dir() == tmp_path / "Local" / "nfdepth" / "data"
    assert nfdepth.default_data_dir is F.default_data_dir and nfdepth.fetch_data is F.fetch_data


# ------------------------------------------------------------------ downloads


def test_fetch_from_a_mirror_then_load(shared, tmp_path, capsys, monkeypatch):
    dest = tmp_path / "data"
    with serve(shared) as (url, seen):
        root = nfdepth.fetch_data(dest, sets=["skimage-motorcycle", "tsukuba"], mirror=url + "/", progress=True)
        assert root == dest.resolve()
        assert len(seen) == 9 and all(p.startswith(("/tsukuba/", "/skimage-motorcycle/")) for p in seen)
        out = capsys.readouterr().out
        assert "tsukuba: 6 files (1.8 MB)" in out and "6 downloaded, 0 already there" in out
        # a second call finds every file intact and downloads nothing
        assert nfdepth.fetch_data(dest, sets=["tsukuba", "skimage-motorcycle"], mirror=url) == root
        assert len(seen) == 9
    for name in ("tsukuba", "skimage-motorcycle"):
        assert (dest / name / "SHA256SUMS").read_text() == (shared / name / "SHA256SUMS").read_text()
        source = (dest / name / "SOURCE.md").read_text(encoding="utf-8")
        assert url in source and "Scharstein" in source and "Terms" in source
    assert not (dest / "middlebury2005").exists()
    assert sorted(p.name for p in (dest / "tsukuba").iterdir()) == sorted(["SHA256SUMS", "SOURCE.md", *(e.path for e in F.data_files("tsukuba"))])
    scene = D.load_tsukuba(root=dest)
    reference = D.load_tsukuba(root=shared)
    np.testing.assert_array_equal(scene.reference, reference.reference)
    np.testing.assert_array_equal(scene.disparity, reference.disparity)
    assert D.load_motorcycle(root=dest).has_metric_depth
    assert D.list_scenes(dest) == ["tsukuba", "motorcycle"]
    # data_root finds the download folder last
    monkeypatch.delenv("NFDEPTH_DATA", raising=False)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(D, "_repo_candidate", lambda: None)
    monkeypatch.setattr(F, "default_data_dir", lambda: dest)
    assert D.data_root() == root


def test_a_source_md_it_did_not_write_is_kept(shared, tmp_path):
    """Fetching into a copy of the project's data replaced each curated SOURCE.md (scale, caveats) by the short one."""
    import shutil

    dest = tmp_path / "data"
    shutil.copytree(shared / "tsukuba", dest / "tsukuba")
    curated = (dest / "tsukuba" / "SOURCE.md").read_text(encoding="utf-8")
    with serve(shared) as (url, seen):
        nfdepth.fetch_data(dest, sets="tsukuba", mirror=url)  # every file intact: nothing downloaded
        assert seen == []
        assert (dest / "tsukuba" / "SOURCE.md").read_text(encoding="utf-8") == curated
        (dest / "tsukuba" / "scene1.row3.col1.ppm").write_bytes(b"P6 1 1 255 abc")  # one file replaced: still not its own
        nfdepth.fetch_data(dest, sets="tsukuba", mirror=url)
        assert len(seen) == 1
        assert (dest / "tsukuba" / "SOURCE.md").read_text(encoding="utf-8") == curated
        # its own SOURCE.md is said again when it downloads (from another origin, say)
        (dest / "tsukuba" / "SOURCE.md").write_text(F._source_text("tsukuba", "http://old.example.org"), encoding="utf-8")
        nfdepth.fetch_data(dest, sets="tsukuba", mirror=url)  # nothing downloaded: kept as it is
        assert "old.example.org" in (dest / "tsukuba" / "SOURCE.md").read_text(encoding="utf-8")
        (dest / "tsukuba" / "scene1.row3.col1.ppm").unlink()
        nfdepth.fetch_data(dest, sets="tsukuba", mirror=url)
        text = (dest / "tsukuba" / "SOURCE.md").read_text(encoding="utf-8")
        assert url in text and "old.example.org" not in text


def test_a_corrupt_local_file_is_replaced(shared, tmp_path):
    dest = tmp_path / "data"
    bad = dest / "tsukuba" / "scene1.row3.col2.ppm"
    bad.parent.mkdir(parents=True)
    bad.write_bytes(b"P6 1 1 255 abc")
    with serve(shared) as (url, seen):
        nfdepth.fetch_data(dest, sets="tsukuba", mirror=url)
    assert len(seen) == 6
    assert bad.read_bytes() == (shared / "tsukuba" / bad.name).read_bytes()


def test_a_corrupt_file_on_the_mirror_is_refused(tmp_path):
    mirror = tmp_path / "mirror"
    (mirror / "tsukuba").mkdir(parents=True)
    (mirror / "tsukuba" / "scene1.row3.col1.ppm").write_bytes(b"P6\n1 1\n255\nabc")
    dest = tmp_path / "data"
    with serve(mirror) as (url, _), pytest.raises(nfdepth.DataDownloadError) as info:
        nfdepth.fetch_data(dest, sets="tsukuba", mirror=url)
    text = str(info.value)
    expected = F.data_files("tsukuba")[0].sha256
    assert "'tsukuba/scene1.row3.col1.ppm'" in text and f"expected {expected}, got " in text
    assert re.search(r"got [0-9a-f]{64}", text) and "try again" in text
    assert info.value.file == "tsukuba/scene1.row3.col1.ppm" and info.value.url.startswith(url)
    assert isinstance(info.value, OSError)
    assert [p for p in dest.rglob("*") if p.is_file()] == []  # no partial, corrupt or temporary file


def test_a_file_missing_on_the_mirror_names_it(tmp_path):
    mirror = tmp_path / "mirror"
    mirror.mkdir()
    dest = tmp_path / "data"
    with serve(mirror) as (url, _), pytest.raises(nfdepth.DataDownloadError, match=r"could not download 'skimage-motorcycle/motorcycle_disp\.npz' .*HTTP 404"):
        nfdepth.fetch_data(dest, sets="skimage-motorcycle", mirror=url)
    assert [p for p in dest.rglob("*") if p.is_file()] == []


def test_missing_pooch_gives_the_install_hint(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "pooch", None)  # `import pooch` now fails
    url = f"http://127.0.0.1:{_closed_port()}"
    with pytest.raises(ModuleNotFoundError, match=r"optional package 'pooch'.*pip install 'nfdepth\[data\]'"):
        nfdepth.fetch_data(tmp_path / "data", sets="tsukuba", mirror=url)
    code, _out, err = run_cli(capsys, "fetch-data", "--dest", tmp_path / "data", "--set", "tsukuba", "--mirror", url)
    assert code == 2 and err.count("\n") == 1
    assert "'pooch'" in err and "pip install 'nfdepth[data]'" in err


# ------------------------------------------------------------------ the command


def test_cli_list_downloads_nothing(tmp_path, capsys):
    code, out, err = run_cli(capsys, "fetch-data", "--list", "--dest", tmp_path / "data")
    assert code == 0 and err == ""
    for name in F.DATA_SETS:
        assert re.search(rf"^{name}\s+\d+\s+[\d.]+ [kM]B\s+not downloaded$", out, flags=re.MULTILINE), out
    assert re.search(r"^total\s+70\s+26\.8 MB", out, flags=re.MULTILINE) and str(tmp_path / "data") in out
    assert not (tmp_path / "data").exists()


def test_cli_bad_set_name(capsys, tmp_path):
    code, _out, err = run_cli(capsys, "fetch-data", "--set", "teddy", "--dest", tmp_path)
    assert code == 2 and err.count("\n") == 1 and "invalid choice: 'teddy'" in err and "middlebury2003-teddy" in err
    assert list(tmp_path.iterdir()) == []


def test_cli_unreachable_mirror(capsys, tmp_path):
    url = f"http://127.0.0.1:{_closed_port()}"
    code, _out, err = run_cli(capsys, "fetch-data", "--set", "tsukuba", "--mirror", url, "--dest", tmp_path / "data")
    assert code == 5 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("nfdepth: error: could not download 'tsukuba/scene1.row3.col1.ppm'") and "connection failed" in err
    assert list(tmp_path.iterdir()) == []  # nor the folders it made for the files


@pytest.mark.parametrize("nested", [False, True])
def test_cli_unreachable_ftp_mirror(capsys, tmp_path, nested):
    """An ftp:// mirror's failure is the same one line and exit code as http's (it was a bare socket error, exit 4);
    its port reaches the connection (pooch took 'host:port' for the host name)."""
    pytest.importorskip("pooch")
    port = _closed_port()
    dest = tmp_path / "a" / "b" if nested else tmp_path / "data"
    code, _out, err = run_cli(capsys, "fetch-data", "--set", "tsukuba", "--mirror", f"ftp://127.0.0.1:{port}/", "--dest", dest)
    assert code == 5
    head = f"nfdepth: error: could not download 'tsukuba/scene1.row3.col1.ppm' from ftp://127.0.0.1:{port}/tsukuba/scene1.row3.col1.ppm: "
    assert re.match(re.escape(head) + r"connection failed \(\[Errno \d+\] Connection refused\); nothing was written for it", err), err
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match=r"^mirror 'ftp://127.0.0.1:x/' has a bad port \(Port could not be cast"):
        F.fetch_data(tmp_path, sets="tsukuba", mirror="ftp://127.0.0.1:x/")


def test_cli_dest_is_a_file(capsys, tmp_path):
    (tmp_path / "f").write_text("x")
    code, _out, err = run_cli(capsys, "fetch-data", "--dest", tmp_path / "f")
    assert code == 4 and err.count("\n") == 1 and "is not a directory" in err


def test_cli_fetch_says_where_and_how(shared, capsys, tmp_path):
    dest = tmp_path / "data"
    with serve(shared) as (url, _):
        code, out, err = run_cli(capsys, "fetch-data", "--set", "tsukuba", "--mirror", url, "--dest", dest)
    assert code == 0, err
    assert f"data ready in {dest.resolve()}" in out and f"NFDEPTH_DATA={dest.resolve()} nfdepth evaluate tsukuba" in out
    code, out, err = run_cli(capsys, "fetch-data", "--list", "--set", "tsukuba", "--dest", dest)
    assert code == 0 and re.search(r"^tsukuba\s+6\s+1\.8 MB\s+present$", out, flags=re.MULTILINE)


@pytest.mark.skipif(sys.platform in ("darwin", "win32"), reason="the default folder follows XDG_CACHE_HOME on Linux only")
def test_cli_default_folder_is_found_automatically(shared, capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.delenv("NFDEPTH_DATA", raising=False)
    monkeypatch.chdir(tmp_path)  # no ../shared/data here
    monkeypatch.setattr(D, "_repo_candidate", lambda: None)  # nor beside the installation
    with serve(shared) as (url, _):
        code, out, err = run_cli(capsys, "fetch-data", "--set", "skimage-motorcycle", "--mirror", url)
    default = tmp_path / "cache" / "nfdepth" / "data"
    assert code == 0, err
    assert f"data ready in {default.resolve()}" in out and "found automatically (from this folder): nfdepth evaluate motorcycle" in out
    assert D.data_root() == default.resolve()
    assert D.list_scenes() == ["motorcycle"]
    # a data folder found first (../shared/data, or one beside the installation): the hint says which, and how to use this one
    monkeypatch.setattr(D, "_repo_candidate", lambda: shared)
    with serve(shared) as (url, _):
        code, out, err = run_cli(capsys, "fetch-data", "--set", "skimage-motorcycle", "--mirror", url)
    assert code == 0, err
    assert "found automatically" not in out
    assert f"use it with: NFDEPTH_DATA={default.resolve()} nfdepth evaluate motorcycle" in out and f"nfdepth finds '{shared.resolve()}' first" in out


# ------------------------------------------------------------------ more refusals and failures


def test_argument_types_are_refused_before_anything_is_created(tmp_path):
    dest = tmp_path / "data"
    with pytest.raises(TypeError) as info:
        F.fetch_data(dest, sets=5)
    assert str(info.value) == f"sets must be a set name or a list of them ({', '.join(F.DATA_SETS)}), got int"
    with pytest.raises(TypeError) as info:
        F.fetch_data(dest, sets="tsukuba", mirror=b"http://127.0.0.1/")
    assert str(info.value) == "mirror must be a URL string such as 'https://data.example.org/nfdepth', got bytes"
    with pytest.raises(TypeError, match=r"^sets must be a set name or a list of them .*, got int$"):
        F.data_files(5)
    assert not dest.exists()


def test_a_folder_where_a_file_belongs(tmp_path, capsys):
    """A folder in the place of a data file is not removed: exit 4 naming it, before any download."""
    dest = tmp_path / "data"
    (dest / "tsukuba" / "scene1.row3.col1.ppm").mkdir(parents=True)
    url = f"http://127.0.0.1:{_closed_port()}"  # never reached
    with pytest.raises(IsADirectoryError) as info:
        F.fetch_data(dest, sets="tsukuba", mirror=url)
    assert str(info.value) == f"cannot write '{dest / 'tsukuba' / 'scene1.row3.col1.ppm'}': it is a folder; remove it and fetch again"
    code, out, err = run_cli(capsys, "fetch-data", "--set", "tsukuba", "--mirror", url, "--dest", dest)
    assert (code, out) == (4, "")
    assert err == f"nfdepth: error: cannot write '{dest / 'tsukuba' / 'scene1.row3.col1.ppm'}': it is a folder; remove it and fetch again\n"
    assert [p for p in dest.rglob("*") if p.is_file()] == []


@pytest.mark.parametrize(
    ("make", "reason"),
    [
        (lambda requests: requests.exceptions.ReadTimeout("HTTPConnectionPool(host='127.0.0.1'): Read timed out. (read timeout=30)"),
         "the connection timed out"),
        (lambda requests: requests.exceptions.TooManyRedirects("Exceeded 30 redirects."), "Exceeded 30 redirects."),
        (lambda requests: requests.exceptions.ChunkedEncodingError(), "ChunkedEncodingError"),
    ],
)
def test_network_failures_are_named(tmp_path, capsys, monkeypatch, make, reason):
    pooch = pytest.importorskip("pooch")
    requests = pytest.importorskip("requests")

    def fail(url, **kwargs):
        raise make(requests)

    monkeypatch.setattr(pooch, "retrieve", fail)
    dest = tmp_path / "data"
    url = "http://127.0.0.1:9"
    code, _out, err = run_cli(capsys, "fetch-data", "--set", "tsukuba", "--mirror", url, "--dest", dest)
    assert code == 5 and err.count("\n") == 1
    assert err == (
        f"nfdepth: error: could not download 'tsukuba/scene1.row3.col1.ppm' from {url}/tsukuba/scene1.row3.col1.ppm: {reason};"
        " nothing was written for it. Check the network connection (or the mirror URL) and run the fetch again:"
        " the files already checked are kept\n"
    )
    assert [p for p in dest.rglob("*") if p.is_file()] == []


def test_cli_fetch_into_the_nfdepth_data_folder_says_so(shared, capsys, tmp_path, monkeypatch):
    """Every file already there (no download, no pooch needed): the hint says NFDEPTH_DATA already points at it."""
    import shutil

    dest = tmp_path / "data"
    (dest / "tsukuba").mkdir(parents=True)
    for e in F.data_files("tsukuba"):
        shutil.copyfile(shared / "tsukuba" / e.path, dest / "tsukuba" / e.path)
    monkeypatch.setenv("NFDEPTH_DATA", str(dest))
    monkeypatch.setitem(sys.modules, "pooch", None)  # nothing to download: pooch is not needed
    code, out, err = run_cli(capsys, "fetch-data", "--set", "tsukuba", "--dest", dest)
    assert code == 0 and err == ""
    assert out.splitlines() == [
        f"tsukuba: 6 files (1.8 MB) in {dest / 'tsukuba'}: 0 downloaded, 6 already there",
        f"data ready in {dest.resolve()} (tsukuba: 6 files checked by SHA-256)",
        "NFDEPTH_DATA points here: nfdepth evaluate tsukuba",
    ]
    assert (dest / "tsukuba" / "SHA256SUMS").read_text() == (shared / "tsukuba" / "SHA256SUMS").read_text()

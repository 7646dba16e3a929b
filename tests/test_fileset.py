"""A set of plain files with a manifest written last (:mod:`mechviz.dynamics.fileset`): a writer
killed with SIGKILL after any of its file-system steps leaves every file whole, and a set that
is either whole (old or new) or refused by the check, which names the file from the other set;
the next writer leaves nothing else; a second writer waits for the first."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from faults import disk_full_at_nth_fsync, killed_after_nth_call

from mechviz.dynamics import fileset
from mechviz.dynamics.files import WriteInterrupted

NAMES = ("a.viser", "a.csv", "a.json")


def make_set(tag: str) -> dict[str, bytes]:
    """Three files, the last a manifest with the size and SHA-256 of the others."""
    files = {"a.viser": f"{tag} viser\n".encode() * 50, "a.csv": f"{tag} csv\n".encode()}
    man = {n: {"bytes": len(b), "sha256": hashlib.sha256(b).hexdigest()} for n, b in files.items()}
    files["a.json"] = json.dumps({"schema_version": 2, "tag": tag, "files": man}).encode()
    return files


OLD, NEW = make_set("old"), make_set("new")


def shown(folder: Path) -> dict[str, bytes]:
    """What a reader sees under the set's names."""
    return {n: (folder / n).read_bytes() for n in NAMES if (folder / n).exists()}


def assert_whole_files(folder: Path, before: dict[str, bytes]) -> None:
    """Every file is whole (its old or its new content), and the set is either one of the
    two, or the check refuses it naming a file whose content is not the manifest's."""
    seen = shown(folder)
    for n, b in seen.items():
        assert b in (before.get(n), NEW[n]), n
    if seen in (before, NEW):
        return
    if "a.json" not in seen:  # a first write cut short: no manifest, nothing to check against
        assert not before
        return
    with pytest.raises(fileset.SetMismatch) as info:
        fileset.check_set(folder, "a.json")
    named = info.value.file
    assert seen[named] != (NEW if seen["a.json"] == NEW["a.json"] else before)[named]
    assert named in str(info.value) and "recording than a.json" in str(info.value)


def tree(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


def assert_nothing_stray(folder: Path) -> None:
    """The names, regular files, and nothing else."""
    assert tree(folder) == sorted(NAMES)
    assert all((folder / n).is_file() and not (folder / n).is_symlink() for n in NAMES)


def write_links_layout(folder: Path, files: dict[str, bytes]) -> None:
    """What the earlier writer left: each name a link into ``.mechviz/a/current/``."""
    home = folder / fileset.OLD_HOME / "a"
    (home / "set-1").mkdir(parents=True)
    for n, b in files.items():
        (home / "set-1" / n).write_bytes(b)
        (folder / n).symlink_to(f"{fileset.OLD_HOME}/a/current/{n}")
    (home / "current").symlink_to("set-1")


def write_plain_layout(folder: Path, files: dict[str, bytes]) -> None:
    """The files themselves, plus temporaries of killed runs of this and older writers."""
    folder.mkdir(exist_ok=True)
    for n, b in files.items():
        (folder / n).write_bytes(b)
    (folder / ".a.viser.4242.partial").write_bytes(b"half")
    (folder / ".a.csv.4242.old").write_bytes(b"older")
    (folder / ".a.json.20260101T000000-1-abcd.partial").write_bytes(b"half")


_CHILD = killed_after_nth_call(
    ("rename", "replace", "symlink", "unlink", "rmdir", "mkdir"),
    """
from pathlib import Path
from mechviz.dynamics import fileset
import json
files = {k: v.encode("latin-1") for k, v in json.loads(sys.stdin.read()).items()}
fileset.write_set(Path(sys.argv[2]), "a", files)
print(count)
""",
)


def run_child(folder: Path, kill_at: int) -> subprocess.CompletedProcess:
    data = json.dumps({k: v.decode("latin-1") for k, v in NEW.items()})
    return subprocess.run(
        [sys.executable, "-c", _CHILD, str(kill_at), str(folder)],
        input=data,
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize("start", ["empty", "set", "links layout", "temporaries"])
@pytest.mark.slow
def test_sigkill_after_any_step_leaves_whole_files_and_the_next_write_cleans_up(tmp_path, start):
    def prepare(folder: Path) -> dict[str, bytes]:
        if start != "empty":
            folder.mkdir()
        if start == "set":
            fileset.write_set(folder, "a", OLD)
            return OLD
        if start == "links layout":
            write_links_layout(folder, OLD)
            return OLD
        if start == "temporaries":
            write_plain_layout(folder, OLD)
            return OLD
        return {}

    probe = tmp_path / "probe"
    prepare(probe)
    done = run_child(probe, 0)
    assert done.returncode == 0, done.stderr
    steps = int(done.stdout)
    assert shown(probe) == NEW
    assert_nothing_stray(probe)
    assert steps >= 2
    for k in range(1, steps + 1):
        folder = tmp_path / f"kill{k}"
        before = prepare(folder)
        res = run_child(folder, k)
        assert res.returncode == -signal.SIGKILL, (k, res.stderr)
        assert_whole_files(folder, before)
        fileset.write_set(folder, "a", make_set(f"next{k}"))
        assert shown(folder) == make_set(f"next{k}")
        assert_nothing_stray(folder)


def test_a_set_replaces_the_links_layout_with_regular_files(tmp_path):
    write_links_layout(tmp_path, OLD)
    assert fileset.check_set(tmp_path, "a.json")[1]["a.csv"] == OLD["a.csv"]  # read through links
    fileset.write_set(tmp_path, "a", NEW)
    assert shown(tmp_path) == NEW
    assert_nothing_stray(tmp_path)


def test_a_file_swapped_from_an_older_set_is_named(tmp_path):
    fileset.write_set(tmp_path / "old", "a", OLD)
    fileset.write_set(tmp_path / "new", "a", NEW)
    old_csv = tmp_path / "old" / "a.csv"
    os.utime(old_csv, (1e9, 1e9))  # recorded long before the new set
    os.replace(old_csv, tmp_path / "new" / "a.csv")
    with pytest.raises(fileset.SetMismatch) as info:
        fileset.check_set(tmp_path / "new", "a.json")
    assert info.value.file == "a.csv"
    assert str(info.value).startswith("a.csv is from an older recording than a.json")
    (tmp_path / "new" / "a.csv").unlink()
    with pytest.raises(fileset.SetMismatch, match=r"a.csv is missing \(a.json lists it\)"):
        fileset.check_set(tmp_path / "new", "a.json")


def test_files_the_new_set_has_not_are_removed_with_the_old_set(tmp_path):
    svg = b"<svg/>"
    old = {"a.svg": svg, **OLD}
    man = json.loads(OLD["a.json"])
    man["files"]["a.svg"] = {"bytes": len(svg), "sha256": hashlib.sha256(svg).hexdigest()}
    old["a.json"] = json.dumps(man).encode()
    fileset.write_set(tmp_path, "a", old)
    assert (tmp_path / "a.svg").read_bytes() == svg
    fileset.write_set(tmp_path, "a", NEW)
    assert_nothing_stray(tmp_path)


def test_an_io_error_before_the_switch_keeps_the_old_set(tmp_path, monkeypatch):
    fileset.write_set(tmp_path, "a", OLD)
    before = tree(tmp_path)
    disk_full_at_nth_fsync(monkeypatch, 2)
    with pytest.raises(OSError, match=r"No space left.*unchanged") as info:
        fileset.write_set(tmp_path, "a", NEW)
    assert info.value.unchanged
    assert shown(tmp_path) == OLD and tree(tmp_path) == before


def test_a_failed_first_write_leaves_no_folder(tmp_path, monkeypatch):
    monkeypatch.setattr(os, "fsync", lambda fd: (_ for _ in ()).throw(OSError(28, "No space")))
    with pytest.raises(OSError, match="No space"):
        fileset.write_set(tmp_path / "new" / "out", "a", NEW)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_after_the_switch_keeps_the_new_set_and_says_so(tmp_path, monkeypatch):
    fileset.write_set(tmp_path, "a", OLD)
    real_replace = os.replace

    def replace_then_interrupt(src, dst):
        real_replace(src, dst)
        if Path(dst).name == "a.json":  # the manifest, renamed last
            signal.raise_signal(signal.SIGINT)

    monkeypatch.setattr(os, "replace", replace_then_interrupt)
    with pytest.raises(WriteInterrupted, match="holds the complete new set") as info:
        fileset.write_set(tmp_path, "a", NEW)
    monkeypatch.undo()
    assert info.value.committed and not info.value.unchanged
    assert shown(tmp_path) == NEW
    assert_nothing_stray(tmp_path)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


_HOLDER = """
import sys
from pathlib import Path
from mechviz.dynamics import fileset
with fileset._Lock(Path(sys.argv[1]), [], None):
    print("locked", flush=True)
    sys.stdin.readline()
"""


@pytest.mark.slow
def test_a_second_writer_waits_for_the_first_and_both_sets_arrive_whole(tmp_path):
    holder = subprocess.Popen(
        [sys.executable, "-c", _HOLDER, str(tmp_path)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        waited = []

        def on_wait(message):
            waited.append(message)
            holder.stdin.write("go\n")  # the holder lets go only once this writer waits
            holder.stdin.flush()

        fileset.write_set(tmp_path, "a", NEW, on_wait=on_wait)
        assert holder.wait(timeout=60) == 0
    finally:
        holder.kill()
        holder.wait()
    assert len(waited) == 1 and "waiting" in waited[0]
    assert shown(tmp_path) == NEW
    assert_nothing_stray(tmp_path)


def test_a_path_too_long_is_refused_before_anything_is_made(tmp_path):
    with pytest.raises(OSError) as info:
        fileset.check_room(tmp_path / ("d" * 5000), "a", list(NAMES))
    assert info.value.errno == 36  # ENAMETOOLONG
    assert list(tmp_path.iterdir()) == []


def test_a_link_in_place_of_the_hidden_folder_is_never_followed_by_the_clean_up(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "precious.txt").write_text("keep me")
    out = tmp_path / "out"
    (out / fileset.OLD_HOME).mkdir(parents=True)
    (out / fileset.OLD_HOME / "a").symlink_to(elsewhere)
    with pytest.raises(OSError, match="not a folder of its own"):
        fileset.write_set(out, "a", NEW)
    assert (elsewhere / "precious.txt").read_text() == "keep me"
    assert sorted(p.name for p in elsewhere.iterdir()) == ["precious.txt"]


@pytest.mark.parametrize("name", ["", ".", "..", "a/b"])
def test_a_set_name_that_is_not_a_plain_name_is_refused(tmp_path, name):
    with pytest.raises(ValueError, match="not a plain set name"):
        fileset.write_set(tmp_path, name, NEW)
    assert list(tmp_path.iterdir()) == []


_TRY_WRITER_LOCK = """
import fcntl, os, sys
fd = os.open(sys.argv[1], os.O_RDONLY | os.O_DIRECTORY)
try:
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    print("free")
except BlockingIOError:
    print("busy")
"""


def test_a_reader_holds_writers_off_while_it_reads(tmp_path):
    fileset.write_set(tmp_path, "a", OLD)

    def writer_could_lock() -> str:
        return subprocess.run(
            [sys.executable, "-c", _TRY_WRITER_LOCK, str(tmp_path)],
            capture_output=True,
            text=True,
            timeout=60,
        ).stdout.strip()

    with fileset.reading(tmp_path):
        assert fileset.check_set(tmp_path, "a.json")[1]["a.csv"] == OLD["a.csv"]
        assert writer_could_lock() == "busy"  # a writer's renames wait for the reading
    assert writer_could_lock() == "free"

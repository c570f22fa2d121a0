"""A forbidden-values map answers only for the files it was built from, and only when undamaged.

* every file the geometry comes from is fingerprinted (meshes included), so an edited mesh
  refuses the map (in :meth:`ForbiddenMap.load` and in the ``forbidden`` backend);
* the ``.agmap`` header, directory and data carry CRC-32s: a flipped bit, an edited header or a
  truncation anywhere is refused with :class:`ForbiddenMapFileError` naming the section;
* a build journal (``.partial``) with a damaged record resumes from what precedes it and gives
  the same bytes as an undisturbed build.

The maps here are tiny (30° and 20° cells, a clearance hook instead of a backend) so the whole
file runs in seconds; the checks do not depend on the resolution.
"""

from __future__ import annotations

import math
import shutil
import struct

import numpy as np
import pytest

import armguard
from armguard import BackendError, ForbiddenMapError
from armguard._errors import ForbiddenMapFileError
from armguard.cspace import ForbiddenMap
from armguard.cspace._format import FORMAT_VERSION, MAGIC
from armguard.harness import repo_root

KW = dict(resolution=math.radians(20.0), cell=(math.radians(40.0), math.radians(40.0)), stopping_distance=0.1,
          max_depth=1)


def wavy_clearance(Q):
    """A clearance hook (m) that forbids some boxes and allows others."""
    Q = np.asarray(Q, dtype=np.float64)
    return 3.0 + 3.0 * np.sin(Q[:, 0]) * np.cos(Q[:, 1] - Q[:, 2])  # HERA's lever arms are ~8.6 m/rad


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    out = tmp_path_factory.mktemp("integrity") / "clean.agmap"
    fmap = ForbiddenMap.build("hermes", out=out, clearance=wavy_clearance, **KW)
    m = fmap.mask()
    assert m.any() and not m.all()  # intervals to damage, and allowed boxes a damaged map could widen
    return fmap


def _flip(path, byte: int, bit: int):
    raw = bytearray(path.read_bytes())
    raw[byte] ^= 1 << bit
    path.write_bytes(bytes(raw))


def _sections(path):
    raw = path.read_bytes()
    n = struct.unpack_from("<I", raw, 12)[0]
    head_end = 24 + n
    return raw, head_end


# ---------------------------------------------------------------------------- item 2: meshes fingerprinted
def _grow_obj(path, factor: float):
    lines = []
    for ln in path.read_text().splitlines():
        if ln.startswith("v "):
            x, y, z = (float(v) * factor for v in ln.split()[1:4])
            ln = f"v {x!r} {y!r} {z!r}"
        lines.append(ln)
    path.write_text("\n".join(lines) + "\n")


def test_an_edited_mesh_refuses_the_map(tmp_path):
    src = tmp_path / "hermes"
    shutil.copytree(repo_root() / "urdf" / "hermes", src)
    model = armguard.load_model(str(src / "hermes.yaml"))
    meshes = sorted((src / "meshes").glob("*.obj"))
    assert set(meshes) <= set(model.files)  # the Model knows the meshes its geometry came from
    out = tmp_path / "h.agmap"
    ForbiddenMap.build(model, out=out, clearance=wavy_clearance, **KW)
    assert {r["name"] for r in ForbiddenMap.load(out).header["model_files"]} >= {p.name for p in meshes}
    armguard.checker(model, "forbidden", {"map": str(out)})  # accepted while nothing changed
    _grow_obj(src / "meshes" / "left_wing_0.obj", 1.6)
    said = r"built for other model files \(changed: left_wing_0\.obj \(sha256 \w{12} in the map, \w{12} now\)\)"
    with pytest.raises(ForbiddenMapError, match=said):
        ForbiddenMap.load(out)
    edited = armguard.load_model(str(src / "hermes.yaml"))
    with pytest.raises(ForbiddenMapError, match=said):
        ForbiddenMap.load(out, model=edited)
    with pytest.raises(BackendError, match=said):
        armguard.checker(edited, "forbidden", {"map": str(out)})


def _mesh_boxes(model) -> set:
    """The world-frame boxes of the model's mesh shapes, names dropped: where the obstacles are, not what they are called."""
    out = set()
    for go in model.collision_model.geometryObjects:
        if str(go.meshPath).endswith(".obj"):
            go.geometry.computeLocalAABB()
            lo, hi = go.geometry.aabb_local.min_, go.geometry.aabb_local.max_
            R, p = go.placement.rotation, go.placement.translation
            corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]) @ R.T + p
            out.add(tuple(np.round(np.concatenate([corners.min(axis=0), corners.max(axis=0)]), 9)))
    return out


def test_meshes_that_exchange_contents_refuse_the_map(tmp_path):
    """Two mesh files that swap their contents keep the set of sha256 the header held, yet move the obstacles."""
    src = tmp_path / "hermes"
    shutil.copytree(repo_root() / "urdf" / "hermes", src)
    urdf = src / "hermes.urdf"
    text = urdf.read_text()
    placed = '<collision name="left_wing_0">\n      <origin xyz="0 0 0" rpy="0 0 0"/>'
    assert text.count(placed) == 1
    urdf.write_text(text.replace(placed, placed.replace('xyz="0 0 0"', 'xyz="0 0 0.5"')))  # the left wing 0.5 m up
    model = armguard.load_model(str(src / "hermes.yaml"))
    out = tmp_path / "h.agmap"
    ForbiddenMap.build(model, out=out, clearance=wavy_clearance, **KW)
    armguard.checker(model, "forbidden", {"map": str(out)})  # accepted while nothing changed
    left, right = src / "meshes" / "left_wing_0.obj", src / "meshes" / "right_wing_0.obj"
    a, b = left.read_bytes(), right.read_bytes()
    left.write_bytes(b)
    right.write_bytes(a)
    swapped = armguard.load_model(str(src / "hermes.yaml"))
    assert sorted(swapped.sha256.values()) == sorted(model.sha256.values())  # the same hashes ...
    assert _mesh_boxes(swapped) != _mesh_boxes(model)  # ... and other obstacles (the right wing's shape 0.5 m up)
    said = (r"changed: left_wing_0\.obj \(sha256 \w{12} in the map, \w{12} now\), "
            r"right_wing_0\.obj \(sha256 \w{12} in the map, \w{12} now\)")
    with pytest.raises(ForbiddenMapError, match=said):
        ForbiddenMap.load(out)
    with pytest.raises(ForbiddenMapError, match=said):
        ForbiddenMap.load(out, model=swapped)
    with pytest.raises(BackendError, match=said):
        armguard.checker(swapped, "forbidden", {"map": str(out)})


def test_model_file_changes_names_what_differs():
    from armguard.cspace._map import model_file_changes

    def rec(name, digit, folder="/a"):
        return {"name": name, "path": f"{folder}/{name}", "sha256": digit * 64}

    base = [rec("m.yaml", "1"), rec("m.urdf", "2"), rec("x.obj", "3"), rec("y.obj", "4")]
    assert model_file_changes(base, [rec(r["name"], r["sha256"][0], "/b") for r in reversed(base)]) == ""  # moved, reordered
    swapped = [rec("m.yaml", "1"), rec("m.urdf", "2"), rec("x.obj", "4"), rec("y.obj", "3")]
    assert model_file_changes(base, swapped) == ("changed: x.obj (sha256 333333333333 in the map, 444444444444 now), "
                                                 "y.obj (sha256 444444444444 in the map, 333333333333 now)")
    assert model_file_changes(base, base[:3] + [rec("z.obj", "4")]) == "in the map only: y.obj 444444444444; new: z.obj 444444444444"
    many = [rec(f"k{i:02d}.obj", "5") for i in range(11)]
    assert model_file_changes(base, base + many).endswith("k07.obj 555555555555 and 3 more")
    twice = [rec("m.yaml", "1"), rec("m.yaml", "1")]  # a name twice (two folders): counted, not merged
    assert model_file_changes(twice, twice[:1]) == "in the map only: m.yaml 111111111111"


def test_a_map_that_records_no_model_files_is_refused(clean, tmp_path):
    from armguard.cspace._format import write_map

    with pytest.raises(ForbiddenMapError, match="model_files: empty"):
        ForbiddenMap.build("hermes", out=tmp_path / "e.agmap", clearance=wavy_clearance, model_files=[], **KW)
    assert not (tmp_path / "e.agmap").exists()
    p = tmp_path / "no_files.agmap"
    write_map(p, {**clean.header, "model_files": []}, [clean.substructure(s) for s in range(clean.grid.n_substructures)])
    with pytest.raises(ForbiddenMapError, match="records no model files"):  # it would answer for any model
        ForbiddenMap.load(p)
    with pytest.raises(ForbiddenMapError, match="records no model files"):
        ForbiddenMap.load(p, model="hermes")


def test_the_kernel_and_format_versions_are_recorded(clean, tmp_path):
    from armguard.cspace._format import KERNEL_VERSION, write_map

    h = clean.header
    assert h["format_version"] == FORMAT_VERSION >= 2 and h["kernel_version"] == KERNEL_VERSION
    assert "armguard" in h
    subs = [clean.substructure(s) for s in range(clean.grid.n_substructures)]
    p = tmp_path / "other_kernel.agmap"
    write_map(p, {**h, "kernel_version": KERNEL_VERSION + 1}, subs)  # well checksummed, another kernel
    with pytest.raises(ForbiddenMapFileError, match=f"kernel version {KERNEL_VERSION + 1}.*rebuild the map"):
        ForbiddenMap.load(p)


# ---------------------------------------------------------------------------- item 3: checksums
def test_every_single_bit_flip_is_refused(clean, tmp_path):
    good = clean.path.read_bytes()
    raw, head_end = _sections(clean.path)
    rng = np.random.default_rng(31)
    # every byte of the preamble, then seeded bytes of the header, the directory and the data
    picks = list(range(24)) + list(rng.integers(24, head_end, 20)) + list(rng.integers(head_end, len(raw), 80))
    p = tmp_path / "flip.agmap"
    sections = set()
    for byte in picks:
        p.write_bytes(good)
        _flip(p, int(byte), int(rng.integers(0, 8)))
        with pytest.raises(ForbiddenMapFileError) as e:
            ForbiddenMap.load(p)
        assert str(p) in str(e.value)
        sections.add(e.value.section.split(",")[0])
    assert {"preamble", "header", "directory", "data"} <= sections


def test_an_edited_header_is_refused(clean, tmp_path):
    raw = clean.path.read_bytes()
    assert raw.count(b'"stopping_distance":0.1') == 1
    p = tmp_path / "edited.agmap"
    p.write_bytes(raw.replace(b'"stopping_distance":0.1', b'"stopping_distance":0.9'))
    with pytest.raises(ForbiddenMapFileError, match="header: checksum mismatch") as e:
        ForbiddenMap.load(p)
    assert e.value.file == str(p) and e.value.section == "header"


@pytest.mark.parametrize("where", ["preamble", "header", "directory", "data", "empty"])
def test_a_truncated_map_is_refused_naming_the_section(clean, tmp_path, where):
    raw, head_end = _sections(clean.path)
    cut = {"preamble": 20, "header": head_end - 5, "directory": head_end + 12, "data": len(raw) - 3, "empty": 0}[where]
    p = tmp_path / "cut.agmap"
    p.write_bytes(raw[:cut])
    with pytest.raises(ForbiddenMapFileError) as e:
        ForbiddenMap.load(p)
    assert e.value.section == ("preamble" if where == "empty" else where) and str(p) in str(e.value)


def test_every_truncation_is_a_located_error(clean, tmp_path):
    """Seeded cuts anywhere (and at every section boundary, where a reader that trusts a length breaks: the
    directory cut gave ``ValueError: buffer is smaller than requested size``) raise ForbiddenMapFileError."""
    from armguard.cspace._format import read_header

    raw, head_end = _sections(clean.path)
    data_off = read_header(clean.path)[3]
    rng = np.random.default_rng(27)
    edges = [0, 8, 12, 24, head_end, data_off, len(raw)]
    cuts = sorted({int(c) for e in edges for c in (e - 1, e, e + 1) if 0 <= c < len(raw)}
                  | {int(c) for c in rng.integers(0, len(raw), 150)})
    p = tmp_path / "cut.agmap"
    for cut in cuts:
        p.write_bytes(raw[:cut])
        with pytest.raises(ForbiddenMapFileError) as e:
            ForbiddenMap.load(p)
        want = ("preamble" if cut < 24 else "header" if cut < head_end else "directory" if cut < data_off else "data")
        assert e.value.section == want, cut


def test_a_version_1_map_is_refused_with_a_rebuild_message(clean, tmp_path):
    raw = clean.path.read_bytes()
    p = tmp_path / "old.agmap"
    p.write_bytes(MAGIC + struct.pack("<II", 1, 8) + b"{}      " + raw[24:])
    with pytest.raises(ForbiddenMapFileError, match=r"format version 1 .*rebuild the map"):
        ForbiddenMap.load(p)


def test_a_well_checksummed_but_invalid_substructure_is_refused(clean, tmp_path):
    """Past the CRC, the pointers and bins must still decode (a writer's bug, not only a flipped bit)."""
    from armguard.cspace._format import read_header, write_map

    header = dict(clean.header)
    subs = [clean.substructure(s) for s in range(clean.grid.n_substructures)]
    s = next(k for k, (_, iv) in enumerate(subs) if len(iv))
    ptr, iv = subs[s]
    iv = iv.copy()
    iv[0, 1] = clean.grid.counts[2] + 5  # beyond the joint-3 bins
    subs[s] = (ptr, iv)
    p = tmp_path / "bad.agmap"
    write_map(p, header, subs)
    read_header(p)  # the sections' checksums hold
    with pytest.raises(ForbiddenMapFileError, match=f"substructure {s}: an interval"):
        ForbiddenMap.load(p)


class _Stop(Exception):
    pass


def _interrupted(tmp_path, k: int):
    out = tmp_path / "r.agmap"

    def stop_after(done, total):
        if done >= k:
            raise _Stop

    with pytest.raises(_Stop):
        ForbiddenMap.build("hermes", out=out, clearance=wavy_clearance, progress=stop_after, **KW)
    return out, tmp_path / "r.agmap.partial"


def test_a_damaged_journal_is_never_trusted(clean, tmp_path):
    out, journal = _interrupted(tmp_path, 6)
    raw = journal.read_bytes()
    n_fp = struct.unpack_from("<I", raw, 8)[0]
    first = 12 + n_fp + 4  # the first record
    # flip a bit inside the third record's intervals: today's journal resumed that as data
    rec = struct.Struct("<IIIQQ")
    pos = first
    for _ in range(2):
        _, n_ptr, n_iv, _, _ = rec.unpack_from(raw, pos)
        pos += rec.size + 2 * (n_ptr + 2 * n_iv) + 4
    _, n_ptr, n_iv, _, _ = rec.unpack_from(raw, pos)
    _flip(journal, pos + rec.size + 2 * n_ptr - 1, 3)  # the last pointer: the interval count of the last cell
    fmap = ForbiddenMap.build("hermes", out=out, clearance=wavy_clearance, **KW)
    r = fmap.build_report
    assert r.reused == 2 and r.computed == clean.grid.n_substructures - 2
    assert "record 2" in r.discarded and "checksum" in r.discarded
    assert out.read_bytes() == clean.path.read_bytes()
    assert np.array_equal(fmap.mask(), clean.mask())


def test_a_journal_cut_short_resumes_and_a_damaged_fingerprint_is_refused(clean, tmp_path):
    out, journal = _interrupted(tmp_path, 5)
    raw = journal.read_bytes()
    journal.write_bytes(raw[:-7])  # the interruption cut the last record
    fmap = ForbiddenMap.build("hermes", out=out, clearance=wavy_clearance, **KW)
    assert fmap.build_report.reused == 4 and "cut short" in fmap.build_report.discarded
    assert out.read_bytes() == clean.path.read_bytes()
    out, journal = _interrupted(tmp_path, 3)
    _flip(journal, 20, 0)  # inside the fingerprint
    with pytest.raises(ForbiddenMapFileError, match="fingerprint"):
        ForbiddenMap.build("hermes", out=out, clearance=wavy_clearance, **KW)
    fmap = ForbiddenMap.build("hermes", out=out, clearance=wavy_clearance, resume=False, **KW)
    assert out.read_bytes() == clean.path.read_bytes()


def test_a_journal_never_yields_a_record_it_was_not_given(clean, tmp_path):
    """Seeded single-bit flips and cuts anywhere in a journal: reading it back either refuses it
    (ForbiddenMapFileError) or yields a prefix of the records written, each exactly as written."""
    from armguard.cspace._build import _journal_check
    from armguard.cspace._format import Journal

    fingerprint = {k: v for k, v in clean.header.items() if k != "stats"}
    check = _journal_check(clean.grid)
    path = tmp_path / "j.partial"
    j = Journal(path, fingerprint, resume=False, check=check)
    written = {s: clean.substructure(s) for s in range(clean.grid.n_substructures)}
    for s, (ptr, iv) in written.items():
        j.append(s, ptr, iv, 10 + s, s % 3)
    j.close()
    good = path.read_bytes()
    rng = np.random.default_rng(3)
    refused = kept = 0
    for pos in rng.integers(0, len(good), 60):
        for damage in ("flip", "cut"):
            raw = bytearray(good)
            if damage == "flip":
                raw[pos] ^= 1 << int(rng.integers(0, 8))
            else:
                del raw[pos:]
            path.write_bytes(bytes(raw))
            try:
                j = Journal(path, fingerprint, check=check)
            except ForbiddenMapFileError:
                refused += 1
                continue
            j.close()
            assert sorted(j.done) == list(range(len(j.done)))  # a prefix
            assert len(j.done) < len(written) and (j.discarded or damage == "cut")  # the damaged record was not kept
            for s, (ptr, iv, ev, un) in j.done.items():
                assert np.array_equal(ptr, written[s][0]) and np.array_equal(iv, written[s][1])
                assert (ev, un) == (10 + s, s % 3)
            kept += len(j.done)
    assert refused and kept  # damage in the fingerprint and in the records were both exercised


def _slow_valid(words, n_cells: int, n_bins: int) -> bool:
    """The decoding rules of one substructure, one loop at a time (the reference for the vectorised check)."""
    w = [int(x) for x in words]
    n = n_cells + 1
    if len(w) < n or (len(w) - n) % 2:
        return False
    ptr, flat = w[:n], w[n:]
    iv = [(flat[2 * t], flat[2 * t + 1]) for t in range(len(flat) // 2)]
    if ptr[0] != 0 or ptr[-1] != len(iv) or any(ptr[c + 1] < ptr[c] for c in range(n_cells)):
        return False
    for c in range(n_cells):
        cell = iv[ptr[c]:ptr[c + 1]]
        if any(not (a < b <= n_bins) for a, b in cell):
            return False
        if any(cell[t + 1][0] < cell[t][1] for t in range(len(cell) - 1)):
            return False
    return True


def test_the_vectorised_substructure_check_equals_the_loop():
    """check_substructures over many substructures at once refuses exactly what the loop refuses, and names the
    first bad one, on encoded random masks with seeded single-word damage."""
    from armguard.cspace._certify import encode_mask
    from armguard.cspace._format import check_substructures

    rng = np.random.default_rng(41)
    n_bins = 9
    refused = 0
    for trial in range(300):
        shapes = [(int(rng.integers(1, 3)), int(rng.integers(1, 3))) for _ in range(int(rng.integers(1, 4)))]
        subs = []
        for c1, c2 in shapes:
            ptr, iv = encode_mask(rng.random((c1, c2, n_bins)) < 0.4)
            subs.append(np.concatenate([ptr, iv.reshape(-1)]).astype(np.uint16))
        k = int(rng.integers(0, len(subs)))
        if trial % 4 and len(subs[k]):
            i = int(rng.integers(0, len(subs[k])))
            subs[k] = subs[k].copy()
            subs[k][i] = int(rng.integers(0, n_bins + 2))
        cells = np.array([c1 * c2 for c1, c2 in shapes])
        bounds = np.concatenate([[0], np.cumsum([len(s) for s in subs])])
        slow = [_slow_valid(s, int(c), n_bins) for s, c in zip(subs, cells)]
        if all(slow):
            check_substructures("x", np.concatenate(subs), bounds, cells, n_bins)
        else:
            refused += 1
            with pytest.raises(ForbiddenMapFileError) as e:
                check_substructures("x", np.concatenate(subs), bounds, cells, n_bins)
            assert e.value.section == f"data, substructure {slow.index(False)}"
    assert 50 < refused < 250  # both kinds were exercised


@pytest.mark.parametrize("field, value", [("step", [float("nan"), 0.1, 0.1]), ("step", [0.0, 0.1, 0.1]),
                                          ("lower", [0.0, float("inf"), 0.0]), ("counts", [0, 3, 3])])
def test_a_well_checksummed_but_invalid_grid_is_refused(clean, tmp_path, field, value):
    """A header whose checksum holds but whose grid is no grid (a NaN or zero step: 'forbidden share nan'
    once; an infinite limit, no cells) is refused when the map is read, never looked up."""
    from armguard import ForbiddenMapError
    from armguard.cspace._format import write_map

    header = dict(clean.header)
    header["grid"] = dict(header["grid"], **{field: value})
    subs = [clean.substructure(s) for s in range(clean.grid.n_substructures)]
    p = tmp_path / "grid.agmap"
    write_map(p, header, subs)
    with pytest.raises(ForbiddenMapError, match="grid record is invalid"):
        ForbiddenMap.load(p)


def test_a_loaded_map_keeps_the_bytes_it_checked(clean, tmp_path):
    """The lookups read the bytes checked when the map was opened, not the file: the deployed file
    overwritten in place afterwards (a ``cp`` over it: same size, other bytes) or truncated changes
    no answer of the map already loaded (mapped from the file, it answered ALLOWED for every
    configuration it had called FORBIDDEN, and a truncated file killed the process with SIGBUS)."""
    from armguard.cspace._format import read_header

    deployed = tmp_path / "deployed.agmap"
    shutil.copy(clean.path, deployed)
    fmap = ForbiddenMap.load(deployed)
    m = armguard.load_model("hermes")
    Q = m.scene_q(m.random_q(2000, 5))
    before = clean.lookup_many(Q)
    _, _, _, data_off = read_header(deployed)
    size = deployed.stat().st_size
    with open(deployed, "r+b") as f:
        f.seek(data_off)
        f.write(bytes(size - data_off))
    np.testing.assert_array_equal(fmap.lookup_many(Q), before)
    with open(deployed, "r+b") as f:
        f.truncate(data_off + 2)
    np.testing.assert_array_equal(fmap.lookup_many(Q), before)
    with pytest.raises(ForbiddenMapFileError):  # opened again, the file is refused
        ForbiddenMap.load(deployed)


@pytest.mark.parametrize("kind", ["fifo", "link"])
def test_a_journal_place_that_is_no_file_is_refused_before_the_build(tmp_path, kind):
    """``OUT.partial`` a FIFO: the build blocked for ever; a link: ``--no-resume`` overwrote the file it names."""
    import os

    journal = tmp_path / "m.agmap.partial"
    notes = tmp_path / "notes.txt"
    notes.write_text("mine\n")
    os.mkfifo(journal) if kind == "fifo" else journal.symlink_to(notes)
    for resume in (True, False):
        with pytest.raises(ForbiddenMapFileError, match="the build journal's place holds a (FIFO|symbolic link)"):
            ForbiddenMap.build("hermes", out=tmp_path / "m.agmap", resolution=math.radians(30), stopping_distance=0.1,
                               max_depth=0, resume=resume)
    assert notes.read_text() == "mine\n" and not (tmp_path / "m.agmap").exists()

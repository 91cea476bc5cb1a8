"""DMGM CAD ``.pt`` reader: exact round trip of a hand-made archive, one shipped pair, refusal of
code-running pickles (the payload must not run), size guards, field checks, and a fuzz test that
only ever yields a view or ``ImportFormatError``."""

from __future__ import annotations

import io
import pickle
import pickletools
import struct
import subprocess
import tempfile
import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cadsim.importers import ImportFormatError
from cadsim.importers.dmgm_pt import DmgmView, iter_pairs, read_view
from cadsim.importers.restricted_pickle import ALLOWLIST, Storage, rebuild_tensor

SHARED = Path("/work/shared/data/dmgm-cad")

# --- a torch.save-style archive, assembled opcode by opcode (protocol 2, as torch writes it) ---

PROTO2, STOP, MARK, TUPLE, TUPLE2 = b"\x80\x02", b".", b"(", b"t", b"\x86"
EMPTY_TUPLE, EMPTY_DICT, SETITEMS, NEWOBJ, BUILD = b")", b"}", b"u", b"\x81", b"b"
REDUCE, BINPERSID, NONE, NEWFALSE = b"R", b"Q", b"N", b"\x89"
STORAGE_OF = {np.dtype(np.float32): "FloatStorage", np.dtype(np.int32): "IntStorage"}


def op_global(module: str, name: str) -> bytes:
    return b"c" + f"{module}\n{name}\n".encode()


def op_str(s: str) -> bytes:
    raw = s.encode()
    return b"X" + struct.pack("<I", len(raw)) + raw


def op_int(i: int) -> bytes:
    return b"J" + struct.pack("<i", i)


def op_tuple(*items: bytes) -> bytes:
    return MARK + b"".join(items) + TUPLE


def op_tensor(key: str, storage: str, numel: int, shape, stride, offset: int = 0) -> bytes:
    """``_rebuild_tensor_v2(persistent storage, offset, size, stride, False, OrderedDict())``."""
    pid = op_tuple(op_str("storage"), op_global("torch", storage), op_str(key), op_str("cpu"))
    pid = pid[:-1] + op_int(numel) + TUPLE + BINPERSID
    hooks = op_global("collections", "OrderedDict") + EMPTY_TUPLE + REDUCE
    args = op_tuple(
        pid,
        op_int(offset),
        op_tuple(*map(op_int, shape)),
        op_tuple(*map(op_int, stride)),
        NEWFALSE,
        hooks,
    )
    return op_global("torch._utils", "_rebuild_tensor_v2") + args + REDUCE


def data_pickle(fields: dict[str, bytes]) -> bytes:
    """``(Data, None)`` with ``fields`` (name -> pickled value) in its GlobalStorage mapping."""
    mapping = EMPTY_DICT + MARK + b"".join(op_str(k) + v for k, v in fields.items()) + SETITEMS
    store = op_global("torch_geometric.data.storage", "GlobalStorage") + EMPTY_TUPLE + NEWOBJ
    store += EMPTY_DICT + MARK + op_str("_mapping") + mapping
    store += op_str("_parent") + b"h\x01" + SETITEMS + BUILD
    data = op_global("torch_geometric.data.data", "Data") + EMPTY_TUPLE + NEWOBJ + b"q\x01"
    data += EMPTY_DICT + MARK
    data += op_str("_edge_attr_cls") + op_global("torch_geometric.data.data", "DataEdgeAttr")
    data += op_str("_tensor_attr_cls") + op_global("torch_geometric.data.data", "DataTensorAttr")
    data += op_str("_store") + store + SETITEMS + BUILD
    return PROTO2 + data + NONE + TUPLE2 + STOP


def archive_bytes(pkl: bytes, storages: dict[str, bytes], version: bytes = b"3\n") -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
        z.writestr("archive/data.pkl", pkl)
        for key, raw in storages.items():
            z.writestr(f"archive/data/{key}", raw)
        z.writestr("archive/version", version)
    return buf.getvalue()


def view_arrays(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "x": rng.random((n, 900), dtype=np.float32),
        "y": rng.choice(np.arange(50000, 62000), n, replace=False).astype(np.float32),
        "pos": rng.normal(0, 20, (n, 3)).astype(np.float32),
        "norm": rng.uniform(0, 1200, (n, 2)).astype(np.float32),
        "pos_world": rng.normal(0, 50, (n, 3)).astype(np.float32),
        "label": rng.integers(0, 8, n).astype(np.int32),
    }


def view_archive(arrays: dict[str, np.ndarray], name: str = "data/proc_s/60260/069_0914") -> bytes:
    """A ``data.pt`` holding ``arrays`` (each its own contiguous storage) and ``name``."""
    fields, storages = {}, {}
    for key, (field, a) in enumerate(arrays.items()):
        a = np.ascontiguousarray(a)
        stride = [int(s) // a.itemsize for s in a.strides]
        fields[field] = op_tensor(str(key), STORAGE_OF[a.dtype], a.size, a.shape, stride)
        storages[str(key)] = a.astype(a.dtype.newbyteorder("<")).tobytes()
    fields["name"] = op_str(name)
    return archive_bytes(data_pickle(fields), storages)


def write(path: Path, blob: bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(blob)
    return path


# --- round trip ---


def test_hand_made_archive_reads_back_exactly(tmp_path):
    arrays = view_arrays(5)
    path = write(tmp_path / "data.pt", view_archive(arrays))
    view = read_view(path)
    assert isinstance(view, DmgmView)
    for field in ("x", "pos", "pos_world", "norm"):
        got = getattr(view, field)
        assert got.dtype == np.float32 and np.array_equal(got, arrays[field]), field
        assert not got.flags.writeable
    assert view.y.dtype == np.int64 and np.array_equal(view.y, arrays["y"].astype(np.int64))
    assert view.label.dtype == np.int64 and np.array_equal(view.label, arrays["label"])
    assert (view.name, view.sequence, view.frame, len(view)) == (
        "data/proc_s/60260/069_0914",
        "069",
        "0914",
        5,
    )


def test_empty_view_reads_as_zero_rows(tmp_path):
    view = read_view(write(tmp_path / "data.pt", view_archive(view_arrays(0))))
    assert view.x.shape == (0, 900) and view.pos_world.shape == (0, 3) and len(view) == 0


def test_rebuild_honours_offset_and_stride():
    values = np.arange(20, dtype="<f4")
    got = rebuild_tensor(Storage("0", values), 2, (3, 4), (1, 3), False, {})
    want = np.array([[values[2 + i + 3 * j] for j in range(4)] for i in range(3)])
    assert np.array_equal(got, want) and got.flags.owndata


def test_iter_pairs_sorted_with_sequence(tmp_path):
    for pair_id, seq in (("100", "071"), ("99", "070")):
        for side, seed in (("proc_s", 1), ("proc_t", 2)):
            name = f"data/{side}/{pair_id}/{seq}_0001"
            write(tmp_path / side / pair_id / "data.pt", view_archive(view_arrays(4, seed), name))
    pairs = list(iter_pairs(tmp_path))
    assert [(p.pair_id, p.sequence) for p in pairs] == [("99", "070"), ("100", "071")]
    pair_id, view_s, view_t, sequence = pairs[0]
    assert np.array_equal(view_s.x, view_arrays(4, 1)["x"])
    assert np.array_equal(view_t.x, view_arrays(4, 2)["x"])


def test_iter_pairs_refuses_unpaired_and_mismatched_frames(tmp_path):
    write(
        tmp_path / "proc_s" / "1" / "data.pt",
        view_archive(view_arrays(3), "data/proc_s/1/069_0001"),
    )
    (tmp_path / "proc_t").mkdir()
    with pytest.raises(ImportFormatError, match=r"\['1'\] are in only one"):
        list(iter_pairs(tmp_path))
    write(
        tmp_path / "proc_t" / "1" / "data.pt",
        view_archive(view_arrays(3), "data/proc_t/1/069_0002"),
    )
    with pytest.raises(ImportFormatError, match="differs from view 1"):
        list(iter_pairs(tmp_path))


def _pair_folder(root: Path, pairs: dict[str, tuple[str, str]], n: int = 3) -> Path:
    """proc_s/<id> and proc_t/<id> for each id -> (name of view s, name of view t)."""
    for pair_id, names in pairs.items():
        for side, name in zip(("proc_s", "proc_t"), names, strict=True):
            write(root / side / pair_id / "data.pt", view_archive(view_arrays(n), name))
    return root


@pytest.mark.parametrize(
    "pairs, n, expected",
    [  # issue 22 #6: names parsed strictly, collisions refused at import
        ({"1": ("data/proc_s/1/069_0001",) * 2}, 3, "claims another pair or side"),  # side t
        ({"1": ("data/proc_s/2/069_0001", "data/proc_t/2/069_0001")}, 3, "claims another pair"),
        ({"1": ("data/proc_s/1/69_0001", "data/proc_t/1/69_0001")}, 3, "3 digits"),
        ({"1": ("data/proc_s/1/069_0001 ", "data/proc_t/1/069_0001 ")}, 3, "is not data/"),
        ({"1": ("data/proc_s/1/069_0001\n", "data/proc_t/1/069_0001\n")}, 3, "is not data/"),
        ({"1": ("data/proc_s/1/\u066069_0001", "data/proc_t/1/069_0001")}, 3, "is not data/"),
        ({"1": ("data/proc_s/1/069_0001", "data/proc_t/1/069_0001")}, 0, "no objects"),
        (
            {
                "1": ("data/proc_s/1/069_0001", "data/proc_t/1/069_0001"),
                "2": ("data/proc_s/2/069_0001", "data/proc_t/2/069_0001"),
            },
            3,
            "pairs 1 and 2 are the same frame 069_0001",
        ),
    ],
)
def test_import_refuses_names_that_collide_or_lie(tmp_path, pairs, n, expected):
    _pair_folder(tmp_path, pairs, n)
    with pytest.raises(ImportFormatError, match=expected):
        list(iter_pairs(tmp_path))


# --- one shipped pair ---

needs_shared = pytest.mark.skipif(not SHARED.is_dir(), reason=f"{SHARED} not present")


@needs_shared
def test_shipped_pair_reads_with_known_values():
    view_s = read_view(SHARED / "proc_s" / "60260" / "data.pt")
    view_t = read_view(SHARED / "proc_t" / "60260" / "data.pt")
    assert (len(view_s), len(view_t), view_s.sequence, view_t.frame) == (6, 5, "069", "0914")
    assert view_s.y[0] == 61256 and view_s.label[0] == 0
    assert np.allclose(view_s.pos[0], [-22.58278, 1.2016526, 22.966326])
    # Descriptor rows have equal norm; world z (up) is near the ground, x/y horizontal.
    norms = np.linalg.norm(view_s.x, axis=1)
    assert np.allclose(norms, norms[0], rtol=1e-4)
    assert np.all((view_s.pos_world[:, 2] > 0.5) & (view_s.pos_world[:, 2] < 3))
    assert len(np.intersect1d(view_s.y, view_t.y)) >= 3


@needs_shared
def test_allowlist_is_exactly_the_globals_of_a_shipped_file():
    with zipfile.ZipFile(SHARED / "proc_t" / "60400" / "data.pt") as z:
        ops = pickletools.genops(z.read("archive/data.pkl"))
        found = {tuple(arg.split(" ")) for op, arg, _ in ops if op.name == "GLOBAL"}
    assert found == set(ALLOWLIST)


@needs_shared
def test_shipped_subset_matches_its_readme_table():
    """The per-sequence regime of the folder's README (and docs/external-data.md), recomputed."""
    rows = {}
    for pair in iter_pairs(SHARED):
        _, i, j = np.intersect1d(pair.view_s.y, pair.view_t.y, return_indices=True)
        gap = pair.view_s.pos_world[i, :2] - pair.view_t.pos_world[j, :2]  # ground plane: x, y
        row = rows.setdefault(pair.sequence, {"ids": [], "objects": [], "covisible": [], "err": []})
        row["ids"].append(int(pair.pair_id))
        row["objects"] += [len(pair.view_s), len(pair.view_t)]
        row["covisible"].append(len(i))
        row["err"] += np.linalg.norm(gap, axis=1).tolist()
    summary = {
        seq: (
            len(r["ids"]),
            min(r["ids"]),
            max(r["ids"]),
            round(float(np.mean(r["objects"])), 1),
            round(float(np.mean(r["covisible"])), 2),
            round(float(np.median(r["err"])), 2),
        )
        for seq, r in rows.items()
    }
    assert summary == {
        "069": (61, 60260, 60320, 7.6, 4.07, 3.37),
        "070": (201, 60321, 60521, 7.8, 4.68, 2.95),
        "071": (48, 60522, 60569, 9.2, 4.65, 2.95),
    }


# --- refusal: nothing from the file runs ---


class _Payload:
    """Pickles as ``func(*args)``: the classic code-running pickle."""

    def __init__(self, func, *args):
        self.func, self.args = func, args

    def __reduce__(self):
        return self.func, self.args


def _payloads(marker: Path) -> dict[str, tuple[object, str]]:
    import os

    return {
        "os.system": (_Payload(os.system, f"touch {marker}"), f"{os.system.__module__}.system"),
        "builtins.eval": (_Payload(eval, f"open({str(marker)!r}, 'w')"), "builtins.eval"),
        "builtins.exec": (_Payload(exec, f"open({str(marker)!r}, 'w')"), "builtins.exec"),
        "subprocess.Popen": (
            _Payload(subprocess.Popen, ["touch", str(marker)]),
            "subprocess.Popen",
        ),
    }


@pytest.mark.parametrize(
    "kind", ["os.system", "builtins.eval", "builtins.exec", "subprocess.Popen"]
)
@pytest.mark.parametrize("protocol", [2, pickle.HIGHEST_PROTOCOL])
def test_code_running_pickle_is_refused_and_does_not_run(tmp_path, kind, protocol):
    marker = tmp_path / "pwned"
    payload, global_name = _payloads(marker)[kind]
    pkl = pickle.dumps((payload, None), protocol=protocol, fix_imports=False)
    path = write(tmp_path / "evil.pt", archive_bytes(pkl, {}))
    with pytest.raises(ImportFormatError) as info:
        read_view(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message
    # Protocol 2 (torch's) names the global; later protocols are refused at their first opcode
    # outside protocol 2 (FRAME, STACK_GLOBAL), before any global is looked up.
    assert (f"refused global '{global_name}'" if protocol == 2 else "opcode") in message
    assert not marker.exists()


def test_payload_inside_a_valid_view_is_refused(tmp_path):
    marker = tmp_path / "pwned"
    arrays = view_arrays(3)
    fields = {
        k: op_tensor(str(i), STORAGE_OF[a.dtype], a.size, a.shape, [a.strides[0] // 4, 1][: a.ndim])
        for i, (k, a) in enumerate(arrays.items())
    }
    fields["name"] = op_global("posix", "system") + op_tuple(op_str(f"touch {marker}")) + REDUCE
    storages = {str(i): a.tobytes() for i, a in enumerate(arrays.values())}
    path = write(tmp_path / "data.pt", archive_bytes(data_pickle(fields), storages))
    with pytest.raises(ImportFormatError, match=r"refused global 'posix\.system'"):
        read_view(path)
    assert not marker.exists()


@pytest.mark.parametrize(
    "pkl, expected",
    [
        # Another torch_geometric class: allowlisting is by exact name, not by package.
        (op_global("torch_geometric.data.hetero_data", "HeteroData") + EMPTY_TUPLE + NEWOBJ,
         "refused global 'torch_geometric.data.hetero_data.HeteroData'"),
        (op_global("torch", "load") + op_tuple(op_str("x.pt")) + REDUCE, "refused global 'torch.load'"),
        # Allowlisted names used other than as the format uses them.
        (op_global("torch_geometric.data.data", "Data") + op_tuple(op_str("a")) + REDUCE,
         "Data created with arguments"),
        (op_global("torch_geometric.data.data", "Data") + EMPTY_TUPLE + REDUCE, "call of torch_geometric"),
        (op_global("torch_geometric.data.data", "DataEdgeAttr") + EMPTY_TUPLE + REDUCE,
         "call of torch_geometric.data.data.DataEdgeAttr"),
        (op_global("torch", "FloatStorage") + EMPTY_TUPLE + REDUCE, "call of torch.FloatStorage"),
        (op_global("collections", "OrderedDict") + op_tuple(op_str("ab")) + REDUCE,
         "OrderedDict with contents"),
        (op_str("x") + EMPTY_TUPLE + REDUCE, "not callable"),
        # Other ways to reach a callable are not opcodes of this format.
        (MARK + op_str("true") + b"ios\nsystem\n", "opcode INST"),
        (MARK + op_global("posix", "system") + op_str("true") + b"o", "opcode OBJ"),
        (b"\x82\x01", "opcode EXT1"),
    ],
)  # fmt: skip
def test_misused_or_unknown_globals_are_refused(tmp_path, pkl, expected):
    path = write(tmp_path / "bad.pt", archive_bytes(PROTO2 + pkl + STOP, {}))
    with pytest.raises(ImportFormatError, match=expected) as info:
        read_view(path)
    assert str(info.value).startswith(str(path))


@pytest.mark.parametrize("module, name", sorted(ALLOWLIST))
@pytest.mark.parametrize(
    "state",
    [
        EMPTY_DICT + op_str("dtype") + op_str("<f8") + b"s",  # __dict__ update
        op_tuple(NONE, EMPTY_DICT + op_str("__defaults__") + op_tuple(op_int(1)) + b"s"),  # setattr
    ],
)
def test_build_cannot_alter_a_stand_in_for_later_files(tmp_path, module, name, state):
    before = {key: repr(value) for key, value in ALLOWLIST.items()}
    path = write(
        tmp_path / "build.pt",
        archive_bytes(PROTO2 + op_global(module, name) + state + BUILD + STOP, {}),
    )
    with pytest.raises(ImportFormatError):
        read_view(path)
    assert {key: repr(value) for key, value in ALLOWLIST.items()} == before
    arrays = view_arrays(2)
    assert np.array_equal(read_view(write(tmp_path / "ok.pt", view_archive(arrays))).x, arrays["x"])


# --- size guards: refused before any large allocation ---


def _one_tensor_view(tensor: bytes, storages: dict[str, bytes]) -> bytes:
    return archive_bytes(
        data_pickle({"x": tensor, "name": op_str("data/proc_s/1/069_0001")}), storages
    )


@pytest.mark.parametrize(
    "tensor, storages, expected",
    [
        (op_tensor("0", "FloatStorage", 2**31 - 1, (2**31 - 1,), (1,)), {"0": b"\0" * 24},
         "declares 2147483647 elements"),
        (op_tensor("0", "FloatStorage", 6, (2**30, 900), (0, 0)), {"0": b"\0" * 24}, "reaches beyond"),
        (op_tensor("0", "FloatStorage", 6, (6,), (1,), offset=2**31 - 1), {"0": b"\0" * 24},
         "reaches beyond"),
        (op_tensor("0", "FloatStorage", 6, (2, 3), (3, 2)), {"0": b"\0" * 24}, "reaches beyond"),
        # an empty axis: no element, but 2**30 rows for whoever walks the first axis
        (op_tensor("0", "FloatStorage", 6, (2**30, 2**30, 0), (0, 0, 0)), {"0": b"\0" * 24},
         "empty tensor of size"),
        (op_tensor("0", "FloatStorage", 6, (1,) * 40, (1,) * 40), {"0": b"\0" * 24}, "up to 32"),
        (op_tensor("7", "FloatStorage", 6, (6,), (1,)), {"0": b"\0" * 24}, "archive/data/7 is missing"),
        (op_tensor("0", "IntStorage", 6, (6,), (1,)) + op_str("x") + op_tensor("0", "FloatStorage", 6, (6,), (1,)),
         {"0": b"\0" * 24}, "two different types"),
    ],
)  # fmt: skip
def test_sizes_beyond_the_bytes_present_are_refused(tmp_path, tensor, storages, expected):
    path = write(tmp_path / "big.pt", _one_tensor_view(tensor, storages))
    assert _refused_peak(path, expected) < 16 * 2**20


def _refused_peak(path: Path, expected: str) -> int:
    """Bytes traced at most while ``read_view(path)`` is refused with a message matching
    `expected`."""
    tracemalloc.start()
    try:
        with pytest.raises(ImportFormatError, match=expected):
            read_view(path)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize(
    "pkl, expected",
    [
        (PROTO2 + b"r\xff\xff\xff\x7f" + STOP, "memo index"),  # LONG_BINPUT 2**31 - 1
        (PROTO2 + b"X\xff\xff\xff\x7fabc", "malformed pickle"),  # BINUNICODE claims 2 GiB
        (PROTO2 + NONE, "malformed pickle"),  # no STOP
        (b"\xffjunk", "malformed pickle"),
    ],
)
def test_malformed_pickle_streams_are_refused(tmp_path, pkl, expected):
    path = write(tmp_path / "bad.pt", archive_bytes(pkl, {}))
    with pytest.raises(ImportFormatError, match=expected):
        read_view(path)


# --- field checks: one line naming file and field ---


@pytest.mark.parametrize(
    "change, field",
    [
        (lambda a: a.update(x=a["x"][:, :899].copy()), "x"),
        (lambda a: a.update(pos=a["pos"][:2].copy()), "pos"),
        (lambda a: a["pos_world"].__setitem__((1, 0), np.nan), "pos_world"),
        (lambda a: a["norm"].__setitem__((0, 1), np.inf), "norm"),
        (lambda a: a["y"].__setitem__(0, 0.5), "y"),
        (lambda a: a["y"].__setitem__(1, a["y"][0]), "y"),
        (lambda a: a.update(label=a["label"].astype(np.float32)), "label"),
        (lambda a: a.pop("pos_world"), "pos_world"),
    ],
)
def test_bad_fields_name_file_and_field(tmp_path, change, field):
    arrays = view_arrays(4)
    change(arrays)
    path = write(tmp_path / "data.pt", view_archive(arrays))
    with pytest.raises(ImportFormatError, match=rf"field '{field}'") as info:
        read_view(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_bad_name_and_wrong_top_level_are_refused(tmp_path):
    path = write(tmp_path / "a.pt", view_archive(view_arrays(2), name="somewhere/else"))
    with pytest.raises(ImportFormatError, match="field 'name'"):
        read_view(path)
    path = write(tmp_path / "b.pt", archive_bytes(PROTO2 + NONE + STOP, {}))
    with pytest.raises(ImportFormatError, match=r"not \(Data, slices\)"):
        read_view(path)
    path = write(tmp_path / "c.pt", archive_bytes(PROTO2 + NONE + STOP, {}, version=b"9\n"))
    with pytest.raises(ImportFormatError, match="version"):
        read_view(path)


# --- fuzz: a view or ImportFormatError, nothing else ---

_VALID = view_archive(view_arrays(3, seed=7))
with zipfile.ZipFile(io.BytesIO(_VALID)) as _z:
    _VALID_PKL = _z.read("archive/data.pkl")
    _VALID_STORAGES = {
        n.rsplit("/", 1)[1]: _z.read(n) for n in _z.namelist() if n.startswith("archive/data/")
    }


def _mutate(blob: bytes, edits: list[tuple[int, int]]) -> bytes:
    out = bytearray(blob)
    for pos, value in edits:
        out[pos % len(out)] = value
    return bytes(out)


_edits = st.lists(st.tuples(st.integers(0, 2**16), st.integers(0, 255)), min_size=1, max_size=6)
_shape = st.lists(st.integers(0, 1000), min_size=0, max_size=3).map(tuple)

_corrupted = st.one_of(
    _edits.map(lambda e: _mutate(_VALID, e)),  # bytes of the zip itself
    st.integers(0, len(_VALID) - 1).map(lambda n: _VALID[:n]),  # truncated zip
    _edits.map(lambda e: archive_bytes(_mutate(_VALID_PKL, e), _VALID_STORAGES)),  # pickle bytes
    st.integers(0, len(_VALID_PKL) - 1).map(
        lambda n: archive_bytes(_VALID_PKL[:n], _VALID_STORAGES)
    ),
    st.tuples(_shape, _shape).map(  # tensors of arbitrary shape over a small storage
        lambda s: _one_tensor_view(op_tensor("0", "FloatStorage", 6, s[0], s[1]), {"0": b"\0" * 24})
    ),
)


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blob=_corrupted)
def test_fuzz_corrupt_archives_give_a_view_or_import_format_error(blob):
    with tempfile.TemporaryDirectory() as d:
        path = write(Path(d) / "data.pt", blob)
        try:
            view = read_view(path)
        except ImportFormatError as exc:
            assert str(exc).startswith(str(path))
        else:
            assert view.x.shape == (len(view), 900)


def _compressed_view(numel: int, compression: int, level: int | None = None) -> bytes:
    """A one-tensor view whose storage (`numel` float32 zeros) is compressed with `compression`."""
    pkl = data_pickle(
        {
            "x": op_tensor("0", "FloatStorage", numel, (numel,), (1,)),
            "name": op_str("data/proc_s/1/069_0001"),
        }
    )
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
        z.writestr("archive/data.pkl", pkl)
        z.writestr(
            "archive/data/0", b"\0" * (4 * numel), compress_type=compression, compresslevel=level
        )
        z.writestr("archive/version", b"3\n")
    return buf.getvalue()


@pytest.mark.parametrize(
    "numel, compression, expected",
    [  # a bzip2 member is refused before a byte is decompressed (its ratio makes small bombs)
        (2**21, zipfile.ZIP_BZIP2, "compression method 12 refused"),
        (2**21, zipfile.ZIP_LZMA, "compression method 14 refused"),
        # a deflated storage larger than any view of this format: refused from the declared
        # element count, before reading
        (2**25, zipfile.ZIP_DEFLATED, "limit"),
    ],
)
def test_decompression_bombs_are_refused_before_anything_is_allocated(
    tmp_path, numel, compression, expected
):
    blob = _compressed_view(numel, compression)
    assert len(blob) < 2**18  # a small file ...
    path = write(tmp_path / "bomb.pt", blob)
    # ... that never gets to allocate what it declares (8-128 MiB)
    assert _refused_peak(path, expected) < 4 * 2**20


def test_a_deflated_view_within_the_limits_still_reads():
    arrays = view_arrays(5)
    buf = io.BytesIO()
    with (
        zipfile.ZipFile(io.BytesIO(view_archive(arrays))) as src,
        zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as dst,
    ):
        for info in src.infolist():
            dst.writestr(info.filename, src.read(info))
    with tempfile.TemporaryDirectory() as tmp:
        view = read_view(write(Path(tmp) / "v.pt", buf.getvalue()))
    np.testing.assert_array_equal(view.x, arrays["x"])

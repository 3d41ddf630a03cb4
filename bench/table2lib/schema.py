"""The chunk file's schema: RESULTS/table2/<material>-<scene>.json is a Chunk, written by
to_dict() in the field order below and read back by from_dict(), which names any key that is
missing, unknown or of the wrong type. test_schema.py loads every committed chunk file and
writes it back byte for byte (docs/bench-table2.md, "Chunk files")."""
from __future__ import annotations

import dataclasses
import glob
import json
import os
import sys
import typing
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

import benchlib

from .config import CHUNK_FORMAT

# A field whose key older chunk files lack: None there, and not written when None.
_ABSENT_WHEN_NONE = {"absent_when_none": True}


def absent_when_none():
    return field(default=None, metadata=_ABSENT_WHEN_NONE)


class SchemaError(ValueError):
    pass


@dataclass(kw_only=True)
class Level:
    """One ladder render at `spp` against the mode's converged render."""
    spp: int
    seed: int
    rel_mse: float
    c: float  # rel_mse / (1/spp + 1/N)
    seconds_per_spp: float
    rays_per_sample: float
    thread_us_per_ray: float


@dataclass(kw_only=True)
class EqualQuality:
    """A mode's ladder and its time to relative MSE 0.01 (stats.equal_quality)."""
    levels: List[Level]
    spp_to_target: float
    seconds_per_spp: float
    seconds_to_target: float
    c_spread: float
    reference_noise: float


@dataclass(kw_only=True)
class FiberReference:
    """The fiber reference's path depth limit, its share of cut paths and, where recorded, the
    parts it was rendered in (--ref-parts) and their seconds summed."""
    max_depth: Optional[int]
    truncated_fraction: Optional[float]
    parts: Optional[int] = absent_when_none()
    seconds: Optional[float] = absent_when_none()


@dataclass(kw_only=True)
class Mode:
    """One mode's converged render (fiber or neural) and its ladder."""
    seconds_per_spp: float
    seconds: float
    build_seconds: float
    embree_bytes: int
    material_bytes: int
    peak_resident_bytes: int
    equal_quality: EqualQuality


@dataclass(kw_only=True)
class EqualTime:
    """Fiber mode given neural mode's time to relative MSE 0.01, and neural at that spp."""
    seconds: float
    fiber_spp: int
    fiber_ssim: float
    fiber_rel_mse: float
    neural_spp: int
    neural_ssim: float
    neural_rel_mse: float


@dataclass(kw_only=True)
class Seeds:
    reference: int
    ladder: int
    equal_time: int


@dataclass(kw_only=True)
class Settings:
    """What a chunk was asked for (bench/table2.py's flags)."""
    size: int
    ref_spp: int
    patch: int
    fiber_ladder: List[int]
    neural_ladder: List[int]
    ref_parts: Optional[int] = absent_when_none()  # absent: one part
    seeds: Seeds
    threads: int
    sampler: str


@dataclass(kw_only=True)
class Provenance:
    """Which weft made the numbers, and where (provenance.py)."""
    weft_commit: Optional[str]
    weft_source_dirty: Optional[bool]
    weft_version: str
    weft_binary_sha256: Optional[str]
    weft_binary_mtime: str
    script_commit: Optional[str]
    script_dirty: bool
    machine: str


@dataclass(kw_only=True)
class Run:
    started: str
    finished: str
    wall_seconds: float
    estimated_minutes: Optional[float]
    command: str


@dataclass(kw_only=True)
class BaselineRun:
    finished: str
    wall_seconds: float


@dataclass(kw_only=True)
class Baseline:
    """The dual-scattering baseline (after ZMA23) of a chunk, against its fiber reference."""
    name: str
    ssim: float
    rel_mse: float
    mean_ratio: List[Optional[float]]
    mean_ratio_source: str
    ssim_scales: Dict[str, float]
    ssim_scales_source: str
    rel_mse_minus_noise: float
    seconds_per_spp: float
    seconds: float
    build_seconds: float
    embree_bytes: int
    material_bytes: int
    peak_resident_bytes: int
    equal_quality: EqualQuality
    speedup_over_fiber: float
    neural_speedup_over_dual: float
    memory_ratio: float
    figure: str
    provenance: Provenance
    run: BaselineRun


@dataclass(kw_only=True)
class Cell:
    """One Table 2 row as measured (a --quick table's rows are Cells)."""
    preset: str
    scene: str
    ref_spp: int
    size: int
    yarn_sampling: Optional[str]
    threads_used: Optional[int]
    scene_stats: Dict[str, Dict[str, Any]]  # weft render's "scene" statistics per mode
    ssim: float
    rel_mse: float
    ssim_scales: Dict[str, float]  # SSIM at K x K pixel blocks, K in PLY_SCALES
    ssim_scales_source: str
    rel_mse_minus_noise: float
    mean_ratio: List[Optional[float]]  # neural / fiber reference mean per channel
    mean_ratio_source: str
    fiber_reference: FiberReference
    fiber: Mode
    neural: Mode
    equal_time: EqualTime
    speedup: float
    memory_ratio: float
    rss_ratio: float
    figure: str  # relative to the results folder


@dataclass(kw_only=True)
class Chunk(Cell):
    """A chunk file: its row, the settings, provenance and run, and the baseline if added."""
    settings: Settings
    provenance: Provenance
    run: Run
    format: int = CHUNK_FORMAT
    dual: Optional[Baseline] = absent_when_none()


@dataclass(kw_only=True)
class AblationRow:
    """One Fig. 5 ablation of a --quick table."""
    scene: str
    variant: str
    ssim: float
    rel_mse: float
    seconds_per_spp: float
    equal_quality: EqualQuality
    time_ratio_to_full: float


# ---- Conversion ----------------------------------------------------------------------------

def from_dict(cls, data, where=None):
    """An instance of the dataclass cls from JSON data; SchemaError names the first key that
    is missing, unknown or of the wrong type."""
    where = where or cls.__name__
    if not isinstance(data, dict):
        raise SchemaError("%s: expected an object, got %s" % (where, type(data).__name__))
    fields = dataclasses.fields(cls)
    unknown = set(data) - {f.name for f in fields}
    if unknown:
        raise SchemaError("%s: unknown key(s) %s" % (where, ", ".join(sorted(unknown))))
    hints = typing.get_type_hints(cls)
    values = {}
    for f in fields:
        if f.name not in data:
            if f.metadata.get("absent_when_none") or f.default is not dataclasses.MISSING:
                continue
            raise SchemaError("%s: missing key %r" % (where, f.name))
        values[f.name] = _read(hints[f.name], data[f.name], "%s.%s" % (where, f.name))
    return cls(**values)


def to_dict(obj):
    """The JSON data of a dataclass instance, keys in field order; fields that older files lack
    are left out when None."""
    out = {}
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if value is None and f.metadata.get("absent_when_none"):
            continue
        out[f.name] = _write(value)
    return out


def _read(tp, value, where):
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Union:  # Optional[X]
        if value is None:
            return None
        (tp,) = [a for a in args if a is not type(None)]
        return _read(tp, value, where)
    if dataclasses.is_dataclass(tp):
        return from_dict(tp, value, where)
    if origin is list:
        _expect(isinstance(value, list), "a list", value, where)
        return [_read(args[0], v, "%s[%d]" % (where, i)) for i, v in enumerate(value)]
    if origin is dict:
        _expect(isinstance(value, dict), "an object", value, where)
        return {k: _read(args[1], v, "%s.%s" % (where, k)) for k, v in value.items()}
    if tp is Any:
        return value
    if tp is float:
        _expect(isinstance(value, (int, float)) and not isinstance(value, bool), "a number",
                value, where)
    elif tp is int:
        _expect(isinstance(value, int) and not isinstance(value, bool), "an integer", value,
                where)
    else:
        _expect(isinstance(value, tp), tp.__name__, value, where)
    return value


def _write(value):
    if dataclasses.is_dataclass(value):
        return to_dict(value)
    if isinstance(value, list):
        return [_write(v) for v in value]
    if isinstance(value, dict):
        return {k: _write(v) for k, v in value.items()}
    return value


def _expect(ok, what, value, where):
    if not ok:
        raise SchemaError("%s: expected %s, got %r" % (where, what, value))


# ---- Files ---------------------------------------------------------------------------------

def chunk_text(chunk):
    """A chunk file's text (indented JSON, as the committed files are)."""
    return json.dumps(to_dict(chunk), indent=1)


def load_chunk(path):
    """The Chunk in a chunk file; SchemaError, naming the file and the key, when the file does
    not hold one."""
    with open(path) as f:
        data = json.load(f)
    if not isinstance(data, dict) or data.get("format") != CHUNK_FORMAT:
        raise SchemaError("%s: not a chunk file of format %d" % (path, CHUNK_FORMAT))
    return from_dict(Chunk, data, path)


def chunk_files(folder):
    """(path, Chunk) of the chunk files in folder (<material>-<scene>.json), by file name; a
    file of another format, or whose name is not its material and scene, is skipped with a
    line on stderr."""
    out = []
    for path in sorted(glob.glob(os.path.join(folder, "*-*.json"))):
        with open(path) as f:
            data = json.load(f)
        if not isinstance(data, dict) or data.get("format") != CHUNK_FORMAT or (
                data.get("preset"), data.get("scene")) != tuple(
                    os.path.basename(path)[:-5].split("-", 1)):
            print("table2: skipping %s (not a chunk file of format %d)" % (path, CHUNK_FORMAT),
                  file=sys.stderr)
            continue
        out.append((path, from_dict(Chunk, data, path)))
    return out


def write_chunk(path, chunk):
    """The chunk file at path (no absolute path of this machine in it: benchlib.portable),
    through a temp file renamed over it."""
    benchlib.write_text(path, json.dumps(benchlib.portable(to_dict(chunk)), indent=1))

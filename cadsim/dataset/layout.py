"""Where things live inside a dataset directory.

```
DIR/manifest.json                  the dataset's manifest (written last; "complete": true when done)
DIR/pairs/e00003_s01/              one record: episode 3, slot 1 (a frame pair, or an N-view snapshot)
DIR/episodes/e00003.json           per-episode summary (resume bookkeeping, generation statistics)
DIR/.tmp-*                         records being written (removed on the next run if left over)
DIR/.work/                         the sources' cache (networks, routes) while generating; removed at the end
DIR/.generate.lock                 the writer lock (``writer_lock``): who is generating into DIR
```
A record's name is its identity (episode, slot), so records computed in parallel or in an
earlier, interrupted run land in the same place.
"""

from __future__ import annotations

import re
from pathlib import Path

MANIFEST = "manifest.json"
PAIRS_DIR = "pairs"
EPISODES_DIR = "episodes"
TEMP_PREFIX = ".tmp-"
WORK_DIR = ".work"
LOCK_FILE = ".generate.lock"

# Files of one record.
VIEW1_PNG = "view1.png"
VIEW2_PNG = "view2.png"
DEPTH_NPZ = "depth.npz"
INSTANCE_NPZ = "instance.npz"
DETECTIONS_NPZ = "detections.npz"
RECORD_JSON = "record.json"
RECORD_FILES = (VIEW1_PNG, VIEW2_PNG, DEPTH_NPZ, INSTANCE_NPZ, DETECTIONS_NPZ, RECORD_JSON)
LIDAR_NPZ = "lidar.npz"  # the views' LiDAR points (records of scenarios with a LiDAR)
IMAGELESS_FILES = (DETECTIONS_NPZ, RECORD_JSON)
MAX_VIEWS = 12  # vehicles (<= 8) + roadside units (<= 4)


def view_png(view: int) -> str:
    """Colour image of view ``view`` (1-based), e.g. ``view3.png``."""
    return f"view{int(view)}.png"


def record_files(views: int, sensor: str = "camera") -> tuple[str, ...]:
    """The files of a record with ``views`` views (2: :data:`RECORD_FILES`); ``sensor``
    "lidar": detections, record and points only; "both": the camera files and the points."""
    if sensor == "lidar":
        return (*IMAGELESS_FILES, LIDAR_NPZ)
    camera = (*(view_png(v) for v in range(1, views + 1)), *RECORD_FILES[2:])
    return (*camera, LIDAR_NPZ) if sensor == "both" else camera


_RECORD_NAME = re.compile(r"^e(\d{5,})_s(\d{2,})$")


def record_name(episode: int, slot: int) -> str:
    """Directory name of record (episode, slot), e.g. ``e00003_s01``."""
    if episode < 0 or slot < 0:
        raise ValueError(f"record identity must be non-negative, got episode={episode} slot={slot}")
    return f"e{episode:05d}_s{slot:02d}"


def parse_record_name(name: str) -> tuple[int, int] | None:
    """(episode, slot) of a record directory name, or None if ``name`` is not one."""
    m = _RECORD_NAME.match(name)
    return (int(m.group(1)), int(m.group(2))) if m else None


def episode_summary_name(episode: int) -> str:
    return f"e{episode:05d}.json"


def existing_records(dataset_dir: Path) -> dict[tuple[int, int], Path]:
    """Complete records on disk, keyed by (episode, slot). Only complete records can exist under
    ``pairs/``: the writer moves a fully written directory there in one rename."""
    pairs = Path(dataset_dir) / PAIRS_DIR
    if not pairs.is_dir():
        return {}
    found = {}
    for entry in pairs.iterdir():
        ident = parse_record_name(entry.name)
        if ident is not None and entry.is_dir():
            found[ident] = entry
    return dict(sorted(found.items()))

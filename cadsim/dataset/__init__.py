"""Frame-pair datasets on disk: format, atomic writer, manifest and reader.

Reading (needs neither SUMO nor pyrender)::

    from cadsim.dataset import Dataset

    ds = Dataset("data/cad")          # len(ds), ds[k], iteration, ds.manifest, ds.checksum
    ds = Dataset("data/cad", verify=True)   # every record and view checked (dataset.verification)
    ds.snapshot(k).pair(i, j)         # an N-view record's views i and j (dataset.multi_view)
    pair = ds[0]
    pair.view1.positions              # (n, 3) metres, view 1's camera frame (x right, y down, z fwd)
    pair.view1.features               # (n, d) float32; also .boxes .object_ids .true_classes .reported_classes .pixels
    pair.gt_pairs                     # (k, 2) int: (i, j) = same object in view1[i] and view2[j]
    problem = pair.problem()          # matchers.Problem
    noisy = pair.redetect(noise_rate=0.05, seed=1)   # new noise on stored clean depth, no render
    pair.color1, pair.depth1, pair.instance1, pair.cameras, pair.objects   # loaded on demand
    pair.observer_poses, pair.camera_extrinsics, pair.camera_to_world      # true poses, 4x4s

    from cadsim.dataset.regime import dataset_regime
    dataset_regime(ds)                # objects per view, covisible, shares, appearance AUC, ...

Layout, every file and field, determinism and resume: docs/dataset.md.
"""

from cadsim.dataset.detections import ViewDetections, ground_truth_pairs, is_acceptable_pair
from cadsim.dataset.manifest import DatasetError
from cadsim.dataset.reader import Dataset, FramePair

__all__ = [
    "Dataset",
    "DatasetError",
    "FramePair",
    "ViewDetections",
    "ground_truth_pairs",
    "is_acceptable_pair",
]

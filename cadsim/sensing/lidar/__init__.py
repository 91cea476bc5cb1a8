"""A ray-cast LiDAR over the renderer's meshes and a box detector on its points.

``beam_pattern`` (which rays, the ``[lidar]`` table), ``mount`` (where the sensor sits),
``scene_triangles`` + ``ray_engine`` + ``raycast`` (one sweep → a :class:`LidarScan`), then the
detector: ``ground_removal`` → ``clustering`` → ``box_fit`` → ``box_detector`` (points →
``ViewDetections``; it never sees the scan's ground-truth object indices). docs/lidar.md
describes the model and its measured speed.
"""

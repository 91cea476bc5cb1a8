"""The V2X study: the camera table (``table.py``, ``markdown.py``, ``report.py``), appearance
realism (``realism.py``), boxes (``boxes.py``), LiDAR (``lidar.py``), camera against LiDAR
(``sensors.py``) and the GNSS preset's calibration check (``gnss_calibration.py``)."""

"""Each agent's own tracks: its detections linked over time from its own positions and
odometry alone (:mod:`matchers.tracking.hungarian`)."""

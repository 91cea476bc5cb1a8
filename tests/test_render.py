"""Off-screen rendering: exact depth, instance ids, scene updates, mesh registry. Tiny hand-made
snapshots, no SUMO simulation; the GL backend is chosen by the code."""

import numpy as np
import pytest
import trimesh
from render_fixtures import H, W, cam

from cadsim.camera import Camera
from cadsim.render import Part, RenderedView, register_mesh, registered_shapes
from cadsim.world import Snapshot, WorldObject

pytestmark = pytest.mark.render


def box(oid, center, size, color=(0.8, 0.1, 0.1), yaw=0.0, shape="box", cls="box", target=True):
    return WorldObject(
        oid, cls, shape, tuple(center), yaw, tuple(size), tuple(color), target=target
    )


def test_depth_of_a_wall_is_exact(renderer):
    # Wall face at x = 10 m, perpendicular to the optical axis: every wall pixel has z = 10 m.
    wall = box(
        "wall", (10.2, 0.0, 3.0), (0.4, 30.0, 6.0), target=False, shape="building", cls="building"
    )
    view = renderer.render(Snapshot(0.0, [wall]), cam())
    assert isinstance(view, RenderedView)
    assert view.color.shape == (H, W, 3) and view.color.dtype == np.uint8
    assert view.depth.dtype == np.float32 and view.instance.dtype == np.int32
    on_wall = view.instance == 0
    assert on_wall[H // 2, W // 2] and on_wall.all(axis=1).sum() > 80  # rows fully on the wall
    np.testing.assert_allclose(view.depth[on_wall], 10.0, atol=2e-3)


def test_depth_of_the_ground_matches_the_ray_geometry(renderer):
    # A road slab with its top at z = 0, camera 2 m above it pitched down 20 degrees.
    road = box(
        "road",
        (40.0, 0.0, -0.05),
        (100.0, 40.0, 0.1),
        color=(0.3, 0.3, 0.3),
        shape="road",
        cls="road",
        target=False,
    )
    c = cam(position=(0.0, 0.0, 2.0), pitch=np.radians(-20.0))
    view = renderer.render(Snapshot(0.0, [road]), c)
    v = np.arange(H // 2 + 10, H, 17)
    u = np.full(v.shape, W // 3)
    uv = np.column_stack([u + 0.5, v + 0.5])
    # Ray through each pixel centre, intersected with the plane z = 0.
    rays_world = c.camera_to_world(c.back_project(uv, np.ones(len(v)))) - np.asarray(c.position)
    t = -c.position[2] / rays_world[:, 2]  # the ray at unit depth scaled to the plane
    assert np.all(view.instance[v, u] == 0)
    np.testing.assert_allclose(view.depth[v, u], t, rtol=1e-3)


def test_instance_ids_index_the_snapshot_objects(renderer):
    red = box("red", (12.0, 3.0, 1.0), (2, 2, 2), color=(0.9, 0.05, 0.05))
    green = box("green", (12.0, 0.0, 1.0), (2, 2, 2), color=(0.05, 0.9, 0.05))
    blue = box("blue", (12.0, -3.0, 1.0), (2, 2, 2), color=(0.05, 0.05, 0.9))
    c = cam()
    for objects in ([red, green, blue], [blue, red, green]):
        view = renderer.render(Snapshot(0.0, objects), c)
        uv = c.project(c.world_to_camera(np.array([o.center for o in objects]))).astype(int)
        ids = view.instance[uv[:, 1], uv[:, 0]]
        assert list(ids) == [0, 1, 2]
        for k, o in enumerate(objects):
            px = view.color[uv[k, 1], uv[k, 0]].astype(int)
            assert np.argmax(px) == int(np.argmax(o.color)), (o.id, px)
        assert set(np.unique(view.instance)) == {-1, 0, 1, 2}


def test_exclude_ids_and_departed_objects(renderer):
    a = box("a", (8.0, 0.0, 1.0), (2, 2, 2))
    b = box("b", (15.0, 0.0, 2.0), (2, 8, 4), color=(0.1, 0.1, 0.9))
    c = cam()
    view = renderer.render(Snapshot(0.0, [a, b]), c, exclude_ids=["a"])
    assert 0 not in np.unique(view.instance) and 1 in np.unique(view.instance)
    view = renderer.render(Snapshot(0.0, [a, b]), c)  # excluded only for that one view
    assert view.instance[H // 2, W // 2] == 0
    view = renderer.render(Snapshot(0.1, [b]), c)  # "a" left the scene
    assert view.instance[H // 2, W // 2] == 0 and set(np.unique(view.instance)) == {-1, 0}
    assert np.isclose(view.depth[H // 2, W // 2], 15.0 - 1.0, atol=2e-3)


def test_every_builtin_shape_renders(renderer):
    shapes = {
        "car": (4.5, 1.8, 1.5), "van": (5.0, 2.0, 2.2), "bus": (12.0, 2.5, 3.2),
        "truck": (9.0, 2.5, 3.4), "bicycle": (1.7, 0.65, 1.7), "person": (0.3, 0.5, 1.75),
        "traffic_light": (0.4, 0.4, 4.0), "sign": (0.05, 0.8, 2.5), "cone": (0.4, 0.4, 0.7),
        "cylinder": (1.0, 1.0, 2.0), "box": (1, 1, 1), "building": (5, 5, 5),
    }  # fmt: skip
    assert set(shapes) <= set(registered_shapes())
    c = cam()
    for shape, size in shapes.items():
        obj = WorldObject(
            "o", shape, shape, (10.0, 0.0, size[2] / 2), np.pi, size, (0.2, 0.5, 0.8), state="G"
        )
        view = renderer.render(Snapshot(0.0, [obj]), c)
        mask = view.instance == 0
        assert mask.sum() > 30, shape
        # The silhouette's height is bounded by the projected 3-D box, and fills most of it.
        rows = np.flatnonzero(mask.any(axis=1))
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (0, 2)], float)
        corners = corners * np.array(size) / 2 + [10.0, 0.0, 0.0]
        v = c.project(c.world_to_camera(corners))[:, 1]
        box_px = v.max() - v.min()
        assert 0.6 * box_px <= rows[-1] - rows[0] + 1 <= box_px + 2, shape


def test_appearance_change_replaces_the_mesh(renderer):
    def light(state, color):
        return WorldObject(
            "tl",
            "traffic_light",
            "traffic_light",
            (6.0, 0.0, 2.0),
            np.pi,
            (0.4, 0.4, 4.0),
            color,
            state=state,
        )

    c = cam(pitch=np.radians(10))
    red = renderer.render(Snapshot(0.0, [light("r", (0.95, 0.05, 0.05))]), c).color.astype(int)
    green = renderer.render(Snapshot(0.5, [light("G", (0.05, 0.95, 0.05))]), c).color.astype(int)
    redness = lambda img: ((img[..., 0] - img[..., 1]) > 80).sum()  # noqa: E731
    greenness = lambda img: ((img[..., 1] - img[..., 0]) > 80).sum()  # noqa: E731
    assert redness(red) > 3 and greenness(red) == 0
    assert greenness(green) > 3 and redness(green) == 0


def test_registered_mesh_builder_is_used_and_unknown_shapes_are_named(renderer):
    def pyramid(spec):
        m = trimesh.creation.cone(radius=0.5, height=1.0, sections=4)
        m.apply_translation((0, 0, -0.5))
        return [Part(m, spec.color)]

    if "test_pyramid" not in registered_shapes():
        register_mesh("test_pyramid", pyramid)
    with pytest.raises(ValueError, match="already registered"):
        register_mesh("test_pyramid", pyramid)
    obj = WorldObject(
        "p", "box", "test_pyramid", (8.0, 0.0, 1.0), 0.0, (2.0, 2.0, 2.0), (0.9, 0.9, 0.1)
    )
    view = renderer.render(Snapshot(0.0, [obj]), cam())
    mask = view.instance == 0
    rows = np.flatnonzero(mask.any(axis=1))
    widths = mask.sum(axis=1)[rows]
    assert widths[0] < widths[-1] / 3  # pointed top, wide base
    bad = WorldObject("q", "box", "no_such_shape", (8.0, 0.0, 1.0), 0.0, (1, 1, 1), (1, 1, 1))
    with pytest.raises(KeyError, match="no_such_shape"):
        renderer.render(Snapshot(0.0, [bad]), cam())


def test_camera_size_must_match(renderer):
    with pytest.raises(ValueError, match="differs from the renderer"):
        renderer.render(Snapshot(0.0, []), Camera(position=(0, 0, 1), yaw=0.0, width=64, height=48))


def test_frustum_culling_leaves_out_only_what_no_pixel_shows(renderer):
    # objects in front, straddling the image border, behind the camera, beyond the far plane and
    # far to the side: the culled render must equal the full one bit for bit
    rng = np.random.default_rng(4)
    objects = [
        box(f"o{k}", (x, y, 1.0), (2.0, 4.0, 2.0), yaw=float(rng.uniform(0, 3)))
        for k, (x, y) in enumerate(rng.uniform(-60, 60, (40, 2)))
    ]
    objects.append(box("far", (700.0, 0.0, 1.0), (4, 4, 4)))
    snapshot, c = Snapshot(0.0, objects), cam()
    culled_ids = renderer._culled(snapshot, renderer._scene.sync(snapshot), c)
    assert "far" in culled_ids and 5 < len(culled_ids) < len(objects)
    renderer.cull = True
    culled = renderer.render(snapshot, c)
    renderer.cull = False
    try:
        full = renderer.render(snapshot, c)
    finally:
        renderer.cull = True
    assert np.array_equal(culled.color, full.color)
    assert np.array_equal(culled.depth, full.depth)
    assert np.array_equal(culled.instance, full.instance)
    # every culled object is really absent from the full render
    index = {o.id: k for k, o in enumerate(objects)}
    assert not set(np.unique(full.instance)) & {index[i] for i in culled_ids}

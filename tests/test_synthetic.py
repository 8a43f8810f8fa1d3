"""Tests of the exact renderer and the paper's synthetic scenes (nfdepth.synthetic).

Ground truth is analytic throughout; each tolerance says where it comes from.
"""

from __future__ import annotations

import numpy as np
import pytest

from nfdepth.camera import PinholeCamera, RigidMotion, image_flow_px
from nfdepth.synthetic import (
    PAPER_EXPERIMENTS,
    CameraMotion,
    ConvexPolyhedron,
    ObjectMotion,
    dynamic_sequence,
    paper_camera,
    paper_dynamic_sequence,
    paper_pyramid,
    paper_static_sequence,
    points_in_camera_frame,
    polygon_coverage,
    relative_motion,
    render,
    surface_depth_at,
)

# Float64 rounding on coordinates of size ~200 px: ~1e-13 per operation.
EXACT = 1e-12


def _box(x0, x1, y0, y1, z0, z1, intensity=100.0):
    """Axis-aligned box; only the front face (Z = z0) is seen from the origin
    when the box straddles the optical axis in X and Y."""
    v = [(x, y, z) for z in (z0, z1) for y in (y0, y1) for x in (x0, x1)]
    # indices: 0..3 at z0 (x0y0, x1y0, x0y1, x1y1), 4..7 at z1
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return ConvexPolyhedron(np.array(v, float), faces, [intensity] * 6)


def _overlap_1d(lo, hi, centres):
    return np.clip(np.minimum(centres + 0.5, hi) - np.maximum(centres - 0.5, lo), 0.0, None)


def _shoelace(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


# --------------------------------------------------------------------------
# Coverage exactness
# --------------------------------------------------------------------------


@pytest.mark.parametrize("reverse", [False, True])
def test_square_coverage_equals_hand_computed_overlaps(reverse):
    xl, xr, yt, yb = 3.27, 9.81, 2.6, 7.05  # fractional offsets in cols and rows
    sq = np.array([(xl, yt), (xr, yt), (xr, yb), (xl, yb)])
    if reverse:
        sq = sq[::-1]
    cov = polygon_coverage(sq, (12, 14))
    expected = np.outer(_overlap_1d(yt, yb, np.arange(12.0)), _overlap_1d(xl, xr, np.arange(14.0)))
    np.testing.assert_allclose(cov, expected, rtol=0, atol=EXACT)


def test_random_triangle_coverage_sums_to_its_area():
    rng = np.random.default_rng(1)
    for _ in range(20):
        tri = rng.uniform(-3.0, 40.0, size=(3, 2))  # partly off the 40x40 image at times
        tri = np.clip(tri, 0.0, 38.0)  # keep it inside so the sum is the whole area
        cov = polygon_coverage(tri, (40, 40))
        # sum of ~40^2 terms each rounded at ~1e-15: 1e-9 is a safe bound
        assert abs(cov.sum() - _shoelace(tri)) < 1e-9
        assert cov.min() >= -EXACT and cov.max() <= 1 + EXACT


def test_triangle_coverage_matches_supersampling():
    tri = np.array([(1.23, 0.71), (7.9, 3.35), (2.6, 6.48)])
    cov = polygon_coverage(tri, (8, 9))
    n = 400
    s = (np.arange(n) + 0.5) / n - 0.5
    (a, b, c) = tri

    def inside(px, py):
        def side(p, q):
            return (q[0] - p[0]) * (py - p[1]) - (q[1] - p[1]) * (px - p[0])

        d1, d2, d3 = side(a, b), side(b, c), side(c, a)
        return ((d1 >= 0) & (d2 >= 0) & (d3 >= 0)) | ((d1 <= 0) & (d2 <= 0) & (d3 <= 0))

    for r, col in [(1, 2), (3, 4), (2, 6), (5, 3), (4, 2)]:  # edge and corner pixels
        sy, sx = np.meshgrid(r + s, col + s, indexing="ij")
        sampled = inside(sx, sy).mean()
        # midpoint sampling of a straight edge errs by < 1/(2n) per edge; up to 3 edges
        assert abs(sampled - cov[r, col]) < 3 / (2 * n), (r, col, sampled, cov[r, col])


# --------------------------------------------------------------------------
# Rendering
# --------------------------------------------------------------------------


def test_pyramid_image_total_is_analytic():
    cam = paper_camera()
    img = render(paper_pyramid(), cam).image
    # base corners project to cx +- 100*300/400 = +-75 px: silhouette 150 x 150,
    # four triangles of 150*75/2 each, all inside the 200 x 200 image
    tri = 150 * 75 / 2
    expected = 255.0 * 200 * 200 + sum((i - 255.0) * tri for i in (50, 100, 150, 200))
    assert abs(img.sum() - expected) < 1e-6  # 4e4 pixels of ~255, rounding ~1e-13 each
    # the face on each side of the image has its documented intensity
    assert img[40, 99] == 50 and img[99, 160] == 100 and img[160, 99] == 150 and img[99, 40] == 200
    assert img[5, 5] == 255


def test_render_depth_is_ray_plane_intersection():
    cam = paper_camera()
    ren = render(paper_pyramid(), cam)
    rng = np.random.default_rng(2)
    rows = rng.integers(0, 200, 400)
    cols = rng.integers(0, 200, 400)
    x, y = cam.to_normalized(rows, cols)
    inside = (np.abs(x) < 0.75) & (np.abs(y) < 0.75)
    # side face planes through the apex (0,0,200) and a base edge at 300 / 400:
    # +X face: Z = 600 / (3 - 2x), and likewise for -X, +Y, -Y
    xmaj = np.abs(x) >= np.abs(y)
    z_expected = np.where(xmaj, 600.0 / (3.0 - 2.0 * np.abs(x)), 600.0 / (3.0 - 2.0 * np.abs(y)))
    got = ren.depth[rows, cols]
    np.testing.assert_allclose(got[inside], z_expected[inside], rtol=1e-9)  # closed form, double rounding
    assert np.all(np.isinf(got[~inside & ((np.abs(x) > 0.76) | (np.abs(y) > 0.76))]))
    # surface_depth_at: the same inside, 400 just outside the base outline
    np.testing.assert_allclose(surface_depth_at(paper_pyramid(), cam, rows[inside], cols[inside]), z_expected[inside], rtol=1e-9)
    out = surface_depth_at(paper_pyramid(), cam, [99.5, 30.0, 174.8], [174.9, 24.0, 99.0])
    np.testing.assert_allclose(out, 400.0, rtol=1e-12)


def test_translation_by_one_pixel_shifts_the_image():
    cam = PinholeCamera(100.0, 60, 50)
    box = _box(-14.3, 15.7, -9.62, 11.15, 100.0, 110.0)  # front face at Z=100: 1 unit = 1 px
    motion = ObjectMotion(translation_per_t=(1.0, 0.0, 0.0))
    a = render(box, cam, object_motion=motion, time=0.0).image
    b = render(box, cam, object_motion=motion, time=1.0).image
    assert render(box, cam).visible_faces == (0,)
    np.testing.assert_allclose(b[:, 1:], a[:, :-1], rtol=0, atol=1e-10)  # 255 * ~1e-13
    # the same shift seen by a camera moving the opposite way
    c = render(box, cam, camera_motion=CameraMotion(velocity_per_t=(-1.0, 0.0, 0.0)), time=1.0).image
    np.testing.assert_allclose(c, b, rtol=0, atol=1e-10)


def test_dtype_and_noise():
    cam = paper_camera(image_size_px=64)
    clean = render(paper_pyramid(), cam, dtype=np.float32).image
    assert clean.dtype == np.float32
    noisy = render(paper_pyramid(), cam, noise_std=2.0, rng=np.random.default_rng(0)).image
    resid = noisy - clean
    assert 1.8 < resid.std() < 2.2  # 4096 samples: std of the estimate ~2/sqrt(8192)


# --------------------------------------------------------------------------
# Motion
# --------------------------------------------------------------------------


@pytest.mark.parametrize("time", [0.0, 1.7])
def test_relative_motion_matches_finite_differences(time):
    cam = PinholeCamera(100.0, 200, 200)
    om = ObjectMotion(rotation_rad_per_t=(0.01, -0.02, 0.015), center=(10.0, -5.0, 380.0), translation_per_t=(0.5, 1.0, 1.5))
    cm = CameraMotion(position=(3.0, -2.0, 1.0), velocity_per_t=(2.0, 0.3, -0.4), rotation_rad_per_t=(0.002, 0.001, -0.003))
    pts = paper_pyramid().vertices
    dt = 1e-3

    def proj(t):
        return cam.project(points_in_camera_frame(pts, object_motion=om, camera_motion=cm, time=t))

    r0, c0, z0 = proj(time)
    rp, cp, _ = proj(time + dt)
    rm, cm_, _ = proj(time - dt)
    fd_col, fd_row = (cp - cm_) / (2 * dt), (rp - rm) / (2 * dt)
    motion = relative_motion(om, cm, time=time)
    fcol, frow = image_flow_px(cam, r0, c0, z0, motion)
    scale = np.max(np.abs(np.concatenate([fcol, frow])))
    # central differences: O(dt^2 * third derivative) ~ 1e-8 relative; rounding eps*200/dt ~ 1e-11
    np.testing.assert_allclose(fcol, fd_col, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(frow, fd_row, rtol=0, atol=1e-6 * scale)


def test_relative_motion_formula_at_time_zero():
    om = ObjectMotion(rotation_rad_per_t=(0.01, 0.02, 0.03), center=(1.0, 2.0, 400.0), translation_per_t=(0.5, 1.0, 1.5))
    cm = CameraMotion(position=(4.0, 0.0, -1.0), velocity_per_t=(2.0, 0.0, 0.0), rotation_rad_per_t=(0.0, 0.001, 0.0))
    got = relative_motion(om, cm)
    want = RigidMotion.about_center(rotation=om.rotation_rad_per_t, center=om.center - cm.position, translation=om.translation_per_t) - RigidMotion(
        cm.velocity_per_t, cm.rotation_rad_per_t
    )
    np.testing.assert_allclose(got.translation, want.translation, rtol=0, atol=EXACT)
    np.testing.assert_allclose(got.rotation, want.rotation, rtol=0, atol=EXACT)


# --------------------------------------------------------------------------
# The paper's sequences
# --------------------------------------------------------------------------


@pytest.mark.parametrize("experiment", [1, 4])
def test_paper_dynamic_sequence(experiment):
    scene = paper_dynamic_sequence(experiment)
    assert scene.frames.shape == (5, 200, 200)
    np.testing.assert_array_equal(scene.times, [-2.0, -1.0, 0.0, 1.0, 2.0])
    assert scene.frame_cameras == ("moving", "stationary", "both", "stationary", "moving")
    np.testing.assert_allclose(scene.relative_motion.translation, [-2.0, 0.0, 0.0], rtol=0, atol=EXACT)
    np.testing.assert_allclose(scene.relative_motion.rotation, 0.0, atol=EXACT)
    assert scene.camera.cx_px == 99.5 and scene.camera.cy_px == 99.5 and scene.camera.focal_px == 100.0
    # I3: both cameras coincide at t = 0, so their renderings are identical
    kw = dict(object_motion=scene.object_motion, time=0.0)
    i3_moving = render(scene.polyhedron, scene.camera, camera_motion=scene.moving_camera, **kw).image
    i3_still = render(scene.polyhedron, scene.camera, camera_motion=scene.stationary_camera, **kw).image
    np.testing.assert_array_equal(i3_moving, i3_still)
    np.testing.assert_array_equal(scene.frames[2], i3_still)
    # object rotation of the table, in radians
    spec = PAPER_EXPERIMENTS[experiment]
    assert np.linalg.norm(scene.object_motion.rotation_rad_per_t) == pytest.approx(np.deg2rad(spec.rotation_deg_per_t), rel=1e-12)
    # at t = 0 every object motion is at its initial pose: the apex (depth 200) on the optical axis
    assert scene.depth_at(99.5, 99.5) == pytest.approx(200.0, rel=1e-12)


def test_paper_experiment_table():
    assert {k: v.paper_max_flow_rel_error for k, v in PAPER_EXPERIMENTS.items()} == {1: 0.01, 2: 0.02, 3: 0.12, 4: 0.05}
    assert [PAPER_EXPERIMENTS[k].rotation_deg_per_t for k in (1, 2, 3, 4)] == [0.1, 0.5, 1.0, 0.5]


def test_dynamic_sequence_stationary_frames_follow_the_object_only():
    # still object: stationary frames equal I3, moving frames differ
    cam = paper_camera(image_size_px=64)
    scene = dynamic_sequence(paper_pyramid(), cam, moving_camera_velocity=(2.0, 0.0, 0.0))
    np.testing.assert_array_equal(scene.frames[1], scene.frames[2])
    np.testing.assert_array_equal(scene.frames[3], scene.frames[2])
    assert np.abs(scene.frames[0] - scene.frames[2]).max() > 1.0
    np.testing.assert_allclose(scene.motion_stationary.translation, 0.0)


def test_paper_static_sequence_motion_and_disparity():
    scene = paper_static_sequence()
    assert scene.frames.shape == (3, 200, 200) and scene.reference_index == 1
    np.testing.assert_allclose(scene.relative_motion.translation, [-2.0, 0.0, 0.0])
    np.testing.assert_allclose(scene.camera_positions[:, 0], [-2.0, 0.0, 2.0])
    # the +X base edge (depth 400) projects at col cx + f (300 - X_cam) / 400:
    # disparity between neighbouring views f b / Z = 100 * 2 / 400 = 0.5 px.
    # Row 99 crosses that edge (x = 0.75 in the reference) between the +X face
    # (100) and the background (255); the edge position is read back exactly
    # from the pixel value that straddles it.
    def edge_col(img):
        row = img[99]
        k = int(np.argmax(row[150:] == 255)) + 150 - 1  # last pixel not pure background
        frac_face = (255.0 - row[k]) / (255.0 - 100.0)  # covered fraction of that pixel
        return k - 0.5 + frac_face

    cols = [edge_col(f) for f in scene.frames]
    np.testing.assert_allclose(np.diff(cols), -100.0 * 2.0 / 400.0, atol=1e-9)  # camera to +X: image moves to -col
    assert scene.depth_at(99.0, cols[1]) == pytest.approx(400.0, rel=1e-12)


# --------------------------------------------------------------------------
# Bad input
# --------------------------------------------------------------------------


def test_bad_input():
    with pytest.raises(ValueError, match="experiment must be one of"):
        paper_dynamic_sequence(5)
    with pytest.raises(TypeError, match="experiment must be one of"):
        paper_dynamic_sequence("1")
    with pytest.raises(ValueError, match="needs rng"):
        paper_static_sequence(noise_std=1.0)
    with pytest.raises(ValueError, match="noise_std must be a finite number >= 0"):
        render(paper_pyramid(), paper_camera(), noise_std=-1.0)
    with pytest.raises(TypeError, match="rng must be a numpy.random.Generator"):
        render(paper_pyramid(), paper_camera(), noise_std=1.0, rng=0)
    with pytest.raises(ValueError, match=r"Z=-?\d.*<= 0"):
        # camera beside the pyramid at Z=300: the +X face is turned toward it, its apex is behind it
        render(paper_pyramid(), paper_camera(), camera_motion=CameraMotion(position=(500.0, 0.0, 300.0)))
    with pytest.raises(ValueError, match="dtype"):
        render(paper_pyramid(), paper_camera(), dtype=np.int32)
    with pytest.raises(ValueError, match="n_views must be an integer >= 2"):
        paper_static_sequence(n_views=1)
    with pytest.raises(ValueError, match="baseline must be a positive finite number"):
        paper_static_sequence(baseline=0.0)
    with pytest.raises(TypeError, match="camera must be a nfdepth.camera.PinholeCamera"):
        render(paper_pyramid(), None)


def test_polyhedron_validation_and_orientation_fix():
    p = paper_pyramid()
    v = p.vertices
    # inward-ordered faces are reversed, so normals point outward
    flipped = ConvexPolyhedron(v, [f[::-1] for f in p.faces], p.intensities)
    assert flipped.faces == p.faces
    centroid = v.mean(axis=0)
    for n, f in zip(flipped.normals, flipped.faces):
        assert n @ (v[list(f)].mean(axis=0) - centroid) > 0
    with pytest.raises(ValueError, match="not convex"):
        # a vertex in front of the apex lies outside the side-face planes
        ConvexPolyhedron(np.vstack([v, [[0.0, 0.0, 100.0]]]), p.faces, p.intensities)
    with pytest.raises(ValueError, match="not planar"):
        w = v.copy()
        w[0, 2] = 390.0
        ConvexPolyhedron(w, p.faces, p.intensities)
    with pytest.raises(ValueError, match="intensities must have shape"):
        ConvexPolyhedron(v, p.faces, [1.0, 2.0])
    with pytest.raises(ValueError, match="outside 0..4"):
        ConvexPolyhedron(v, [(0, 1, 9)] + list(p.faces[1:]), p.intensities)


@pytest.mark.parametrize(
    ("edit", "exc", "message"),
    [
        (lambda v, f, i: ("abc", f, i), TypeError, "vertices must be an (N, 3) array of numbers, got 'abc'"),
        (lambda v, f, i: (v[:, :2], f, i), ValueError, "vertices must have shape (N, 3) with N >= 4, got shape (5, 2)"),
        (lambda v, f, i: (v[:3], f, i), ValueError, "vertices must have shape (N, 3) with N >= 4, got shape (3, 3)"),
        (lambda v, f, i: (np.where(np.arange(15).reshape(5, 3) == 4, np.nan, v), f, i), ValueError, "vertices must be finite"),
        (lambda v, f, i: (v, [(0, 1, "x")] + f[1:], i), TypeError, "faces must be a sequence of sequences of vertex indices, got [(0, 1, 'x'), "),
        (lambda v, f, i: (v, 7, i), TypeError, "faces must be a sequence of sequences of vertex indices, got 7"),
        (lambda v, f, i: (v, f[:3], i[:3]), ValueError, "faces must hold at least 4 faces for a closed solid, got 3"),
        (lambda v, f, i: (v, f, ["a"] * 5), TypeError, "intensities must be numbers, got ['a', 'a', 'a', 'a', 'a']"),
        (lambda v, f, i: (v, f, [1.0, 2.0, np.inf, 4.0, 5.0]), ValueError, "intensities must be finite, got [1.0, 2.0, inf, 4.0, 5.0]"),
        (lambda v, f, i: (np.zeros((5, 3)), f, i), ValueError, "vertices must not all coincide"),
        (lambda v, f, i: (v, [(0, 1)] + f[1:], i), ValueError, "faces[0] must list at least 3 distinct vertex indices, got (0, 1)"),
        (lambda v, f, i: (v, f[:1] + [(1, 2, 2)] + f[2:], i), ValueError, "faces[1] must list at least 3 distinct vertex indices, got (1, 2, 2)"),
        (lambda v, f, i: (v, f[:2] + [(-1, 0, 1)] + f[3:], i), ValueError, "faces[2] has a vertex index outside 0..4: (-1, 0, 1)"),
    ],
)
def test_polyhedron_refuses_bad_definitions(edit, exc, message):
    p = paper_pyramid()
    v, f, i = edit(p.vertices.copy(), list(p.faces), list(p.intensities))
    with pytest.raises(exc) as info:
        ConvexPolyhedron(v, f, i)
    assert str(info.value).startswith(message), str(info.value)
    assert type(info.value) is exc


def test_polyhedron_refuses_degenerate_and_non_convex_faces():
    # a unit cube; face 0 is the bottom square (0, 1, 3, 2) in the z = 0 plane
    v = np.array([(x, y, z) for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    cube = ConvexPolyhedron(v, faces, [1.0] * 6)
    assert len(cube.faces) == 6
    # three collinear vertices: a face of zero area
    w = np.vstack([v, [(0.5, 0.0, 0.0)]])
    with pytest.raises(ValueError, match=r"^faces\[0\] \(0, 8, 1\) is degenerate \(zero area\)$"):
        ConvexPolyhedron(w, [(0, 8, 1)] + faces[1:], [1.0] * 6)
    # the bottom square with a dent: a reflex vertex at (0.5, 0.3, 0)
    w = np.vstack([v, [(0.5, 0.3, 0.0)]])
    with pytest.raises(ValueError, match=r"^faces\[0\] \(0, 8, 1, 3, 2\) is not a convex polygon in the given vertex order$"):
        ConvexPolyhedron(w, [(0, 8, 1, 3, 2)] + faces[1:], [1.0] * 6)


def test_polygon_coverage_bad_input_and_empty_cases():
    tri = [(1.0, 1.0), (5.0, 1.0), (1.0, 4.0)]
    for bad, message in (([(0, 0), (1, 1)], "vertices_px must have shape (M, 2) with M >= 3, got shape (2, 2)"),
                         ([(0, 0, 0)] * 3, "vertices_px must have shape (M, 2) with M >= 3, got shape (3, 3)"),
                         ([(0, 0), (1, np.nan), (2, 0)], "vertices_px must be finite")):
        with pytest.raises(ValueError) as info:
            polygon_coverage(bad, (8, 8))
        assert str(info.value) == message
    with pytest.raises(TypeError, match=r"^shape must be \(rows, cols\) of integers, got 8$"):
        polygon_coverage(tri, 8)
    with pytest.raises(ValueError, match=r"^shape must be positive, got \(0, 8\)$"):
        polygon_coverage(tri, (0, 8))
    # wholly outside the image, or of zero area (collinear vertices): no coverage
    np.testing.assert_array_equal(polygon_coverage([(20.0, 20.0), (30.0, 20.0), (20.0, 30.0)], (8, 8)), np.zeros((8, 8)))
    np.testing.assert_array_equal(polygon_coverage([(1.0, 1.0), (3.0, 3.0), (6.0, 6.0)], (8, 8)), np.zeros((8, 8)))
    assert polygon_coverage(tri, (8, 8)).sum() == pytest.approx(6.0, abs=EXACT)  # the area, 4 x 3 / 2


def test_render_an_object_outside_the_view():
    """A face turned toward the camera but projected beside the image covers no pixel: background and infinite depth."""
    box = _box(1000.0, 1100.0, -50.0, 50.0, 300.0, 400.0, intensity=10.0)
    r = render(box, paper_camera(), background=255.0)
    assert 0 in r.visible_faces  # the front face (Z = 300) is turned toward the camera
    np.testing.assert_array_equal(r.image, np.full((200, 200), 255.0))
    assert np.all(np.isinf(r.depth))


def test_points_sequences_and_types_refused():
    with pytest.raises(ValueError, match=r"^points must have shape \(\.\.\., 3\), got \(4, 2\)$"):
        points_in_camera_frame(np.zeros((4, 2)))
    with pytest.raises(TypeError, match=r"^object_motion must be a ObjectMotion or None, got str$"):
        points_in_camera_frame(np.zeros((1, 3)), object_motion="spin")
    with pytest.raises(TypeError, match=r"^polyhedron must be a ConvexPolyhedron, got NoneType$"):
        render(None, paper_camera())
    from nfdepth.synthetic import static_sequence

    with pytest.raises(ValueError, match=r"^reference_index must be in 0\.\.2, got 3$"):
        static_sequence(paper_pyramid(), paper_camera(), n_views=3, reference_index=3)
    scene = static_sequence(paper_pyramid(), paper_camera(image_size_px=40), n_views=3, reference_index=2)
    assert scene.reference_index == 2


def test_video_sequence_of_a_turning_camera():
    """Frame k is the render at t = k - reference; poses follow the motion; depth_at is the render's depth."""
    from nfdepth.synthetic import video_sequence

    motion = CameraMotion(position=(5.0, 0.0, 0.0), velocity_per_t=(2.0, 0.0, 1.0), rotation_rad_per_t=(0.0, 0.02, 0.01))
    cam = paper_camera(image_size_px=40)
    scene = video_sequence(paper_pyramid(), cam, camera_motion=motion, n_frames=4)
    np.testing.assert_array_equal(scene.times, [-2.0, -1.0, 0.0, 1.0])
    np.testing.assert_allclose(scene.positions, [[1.0, 0, -2.0], [3.0, 0, -1.0], [5.0, 0, 0], [7.0, 0, 1.0]])
    np.testing.assert_allclose(scene.orientations_rad, [[0, -0.04, -0.02], [0, -0.02, -0.01], [0, 0, 0], [0, 0.02, 0.01]])
    for k, t in enumerate(scene.times):
        rendering = render(paper_pyramid(), cam, camera_motion=motion, time=t)
        np.testing.assert_array_equal(scene.frames[k], rendering.image)
        rows, cols = np.mgrid[0:40, 0:40]
        np.testing.assert_allclose(scene.depth_at(k, rows, cols), rendering.depth)
    with pytest.raises(TypeError, match="camera_motion must be a CameraMotion, got NoneType"):
        video_sequence(paper_pyramid(), cam, camera_motion=None)
    with pytest.raises(ValueError, match="reference_index must be in 0..3, got 4"):
        video_sequence(paper_pyramid(), cam, camera_motion=motion, n_frames=4, reference_index=4)

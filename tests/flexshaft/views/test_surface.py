"""3D mode pictures: the geometry of the deformation against closed forms, then the pixels."""

from __future__ import annotations

import numpy as np
import pytest

import flexshaft as fs
from flexshaft.cli import main
from flexshaft.sections import table_from_segments
from flexshaft.views.deformed import mode_surface
from tests.conftest import EXAMPLES

L, D, N = 2.0, 0.1, 80


@pytest.fixture(scope="module")
def rod():
    t = table_from_segments([{"length": L, "od": D}], name="rod")
    s = fs.Shaft.from_sections("rod", t, fs.STEEL, max_element_length=L / N)
    return fs.modal_analysis(fs.Drivetrain("rod", [s]), 3)


def test_every_surface_point_turns_by_the_exact_modal_angle(rod):
    # A free uniform rod of linear elements with consistent inertia has the sampled cos(πx/L) as its
    # exact first mode, so the drawn twist at every point is scale·cos(πx/L) (up to sign) to round-off.
    scale = 0.3
    S = mode_surface(rod, 1, scale=scale)
    x, y, z = S.points.T
    sign = np.sign(S.theta[np.argmin(x)])
    phi = scale * sign * np.cos(np.pi * x / L)
    # Round-off of the mode (eps·λ_max/gap ~ 6e-13 of the 0.3 rad twist, 80 elements) on a 0.05 m
    # radius: ~1e-14 m.
    np.testing.assert_allclose(S.deformed[:, 1], y * np.cos(phi) - z * np.sin(phi), atol=1e-12)
    np.testing.assert_allclose(S.deformed[:, 2], y * np.sin(phi) + z * np.cos(phi), atol=1e-12)
    # The surface is the shaft's: radius D/2 everywhere (a solid round section's equivalent annulus),
    # r·cos and r·sin back through hypot: a few roundings.
    np.testing.assert_allclose(np.hypot(y, z), D / 2, rtol=1e-12)


def test_stress_colour_is_g_r_dtheta_dx(rod):
    # τ = G·r·dθ/dx at 1 mrad peak; dθ/dx from the elements: second-order accurate inside
    # (the mean of two element slopes), first-order at the free ends, where one element of
    # length h gives the slope at h/2: an error of at most G·r·(π/L)·sin(πh/2L)·amplitude.
    S = mode_surface(rod, 1, colour="stress")
    x = S.points[:, 0]
    sign = np.sign(S.theta[np.argmin(x)])
    G, r, amp = fs.STEEL.G, D / 2, S.amplitude
    exact = -G * r * (np.pi / L) * np.sin(np.pi * x / L) * sign * amp / 1e6  # MPa
    peak = G * r * np.pi / L * amp / 1e6
    bound = peak * np.sin(np.pi * (L / N) / (2 * L))
    assert np.max(np.abs(S.scalars - exact)) <= 1.01 * bound
    assert S.unit == "MPa"


def test_a_rigid_mode_and_a_bad_colour_are_refused(rod):
    with pytest.raises(fs.ModelError, match="mode = 0: is a rigid-body mode"):
        mode_surface(rod, 0)
    with pytest.raises(fs.ModelError, match="colour = 'blue'"):
        mode_surface(rod, 1, colour="blue")


@pytest.fixture(scope="module")
def c1():
    return fs.modal_analysis(fs.load_model(EXAMPLES / "customer1.toml"))


def test_pictures_of_two_modes_are_not_blank_and_differ(tmp_path, c1):
    pytest.importorskip("pyvista")
    import imageio.v3 as iio

    a, b = tmp_path / "a.png", tmp_path / "b.png"
    c1.view(1, a)
    c1.view(3, b, colour="stress")
    ia, ib = iio.imread(a).astype(float), iio.imread(b).astype(float)
    assert ia.shape == ib.shape and ia.std() > 5 and ib.std() > 5  # something drawn on the white
    assert np.mean(np.abs(ia - ib)) > 1.0  # and not the same picture
    with pytest.raises(fs.ModelError, match="file exists"):
        c1.view(1, a)


def test_a_gif_has_the_frames_asked_for(tmp_path, c1, capsys):
    # sin(2πk/n) is symmetric about the peak, so frames k and n/2 - k draw the same shape: a GIF writer
    # merged them (10 asked, 8 written). Each frame carries its phase mark, so all n stay.
    pytest.importorskip("pyvista")
    import imageio.v3 as iio

    out = tmp_path / "m.gif"
    c1_file = str(EXAMPLES / "customer1.toml")
    assert main(["view", c1_file, "--mode", "2", "--frames", "10", "-o", str(out)]) == 0
    assert "mode 2 " in capsys.readouterr().out
    assert iio.imread(out, index=None).shape[0] == 10
    assert main(["view", str(EXAMPLES / "customer1.toml"), "--mode", "7", "-o", str(out), "--force"]) == 2
    assert "--mode = 7: no such mode; valid: 0 … 4" in capsys.readouterr().err


@pytest.mark.slow
def test_thirty_frames_and_motion_one_can_see(tmp_path, c1):
    pytest.importorskip("pyvista")
    import imageio.v3 as iio

    out = tmp_path / "m.gif"
    from flexshaft.views.render import mode_gif

    mode_gif(c1, 2, out, frames=30)
    g = iio.imread(out, index=None).astype(float)
    assert g.shape[0] == 30
    # a quarter period and three quarters: the whole deflection reversed, its colours too
    changed = np.any(np.abs(g[7] - g[22]) > 2, axis=-1)
    assert changed.mean() >= 0.02


def test_labels_never_overlap(c1):
    pytest.importorskip("pyvista")
    from flexshaft.views.render import compose, mode_figure

    def boxes(fig):
        fig.canvas.draw()  # the label boxes take their size and place when drawn
        r = fig.canvas.get_renderer()
        texts = [t for t in fig.axes[0].texts if t.get_bbox_patch() is not None]
        return [t.get_bbox_patch().get_window_extent(r) for t in texts]

    def overlapping(bbs):
        return [(i, j) for i in range(len(bbs)) for j in range(i) if bbs[i].overlaps(bbs[j])]

    fig = mode_figure(c1, 2)
    bbs = boxes(fig)
    assert len(bbs) == 6 and not overlapping(bbs)  # parts 1-4, motor, generator
    W, H = fig.bbox.width, fig.bbox.height
    assert all(b.x0 >= 0 and b.y0 >= 0 and b.x1 <= W and b.y1 <= H for b in bbs)
    # crowded: eight labels on one spot still find their own rows
    img = np.ones((300, 600, 3))
    crowd = compose(
        img,
        anchors=np.full((8, 2), 300.0),
        texts=[f"station {k}" for k in range(8)],
        below=[False] * 8,
        colour="twist",
        unit="mrad",
        limits=(-1.0, 1.0),
        cmap="coolwarm",
        title="t\nt",
        metres_per_pixel=0.01,
        axes=np.array([[1.0, 0], [0.3, -0.3], [0, -1.0]]),
    )
    assert not overlapping(boxes(crowd))
    # the colour bar's ticks are round numbers (1, 2 or 5 times a power of ten, times an integer)
    bar = fig.axes[1]
    ticks = [t for t in bar.get_yticks() if bar.get_ylim()[0] <= t <= bar.get_ylim()[1]]
    step = np.diff(ticks)
    assert len(ticks) >= 3 and np.allclose(step, step[0])
    mantissa = step[0] / 10 ** np.floor(np.log10(step[0]))
    assert min(abs(mantissa - m) for m in (1, 2, 5, 10)) < 1e-9
    assert all(abs(t / step[0] - round(t / step[0])) < 1e-9 for t in ticks)


def test_the_twist_tests_stress_colour_is_t_r_over_j(tmp_path):
    # Statics is exact: a tube under torque T carries τ = T·r/J at its surface, whatever the mesh.
    od, id_, T = 0.28, 0.18, 86_000.0
    t = table_from_segments([{"length": 1.5, "od": od, "id": id_}], name="tube")
    d = fs.Drivetrain(
        "t",
        [
            fs.Rigid("m", 1.0),
            fs.Shaft.from_sections("tube", t, fs.STEEL, max_element_length=0.1),
            fs.Rigid("g", 1.0),
        ],
    )
    twist = fs.twist_test(d, T)
    from flexshaft.views.deformed import twist_surface

    S = twist_surface(d, twist)
    J = np.pi / 32 * (od**4 - id_**4)
    # the twist test's 15-element solve (condition ~100) and the slope: ~1e-14; 1e-9 is loose
    np.testing.assert_allclose(S.scalars, T * (od / 2) / J / 1e6, rtol=1e-9)
    assert S.unit == "MPa" and S.amplitude == pytest.approx(np.max(np.abs(twist.theta)))
    pytest.importorskip("pyvista")
    out = tmp_path / "twist.png"
    assert main(["twist", str(EXAMPLES / "customer1.toml"), "--view", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_cad_part_is_drawn_from_its_own_surface_turned_by_the_mode():
    pytest.importorskip("build123d")
    r = fs.modal_analysis(fs.load_model(EXAMPLES / "customer1_cad.toml"), 6)
    S = mode_surface(r, 2)
    assert S.triangles.shape[0] > 1000  # parts 1 and 2 from their tessellated solids
    # Every point is its undeformed self turned about the axis by the drawn twist at its x (a rotation
    # of coordinates < 0.3 m: a few roundings, ~1e-16 m).
    x, y, z = S.points.T
    np.testing.assert_allclose(S.deformed[:, 1], y * np.cos(S.phi) - z * np.sin(S.phi), atol=1e-12)
    np.testing.assert_allclose(S.deformed[:, 2], y * np.sin(S.phi) + z * np.cos(S.phi), atol=1e-12)
    # The drawn twist is the max-normalised mode interpolated along part 1's own nodes, exactly.
    model = r.model
    theta = r.dof_shapes("θx")[:, 2]
    theta = theta / np.max(np.abs(theta[model.station_nodes]))
    s, e = int(model.start_node[1]), int(model.end_node[1])
    inside = (x > model.x[s] + 1e-9) & (x < model.x[e] - 1e-9)
    assert inside.sum() > 100
    expected = np.interp(x[inside], model.x[s : e + 1], theta[s : e + 1])
    np.testing.assert_allclose(S.phi[inside] / S.scale, expected, atol=1e-12)  # the same interpolation

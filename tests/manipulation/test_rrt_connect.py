"""The arm's planning scene and RRT-Connect: a Panda (example-robot-data, its collision meshes)
beside a wall. Paths are checked again on the exact meshes at 0.01 rad per joint."""

from __future__ import annotations

import dataclasses
import itertools
from typing import cast

import numpy as np
import pytest

from bt_manip.manipulation.collision_scene import CollisionScene, Obstacle, never_colliding_pairs
from bt_manip.manipulation.rrt_connect import PlanError, PlanOptions, path_length, plan
from bt_manip.sim.assets import example_robot_data_share

PANDA = example_robot_data_share() / "example-robot-data/robots/panda_description/urdf/panda.urdf"
JOINTS = [f"panda_joint{i}" for i in range(1, 8)]
HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
LEFT = np.array([1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.785])
RIGHT = np.array([-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.785])


def _pose(x: float, y: float, z: float) -> tuple[tuple[float, ...], ...]:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return tuple(map(tuple, m))


WALL = Obstacle("wall", "box", (0.3, 0.05, 0.9), _pose(0.5, 0.0, 0.45))


def _scene(exact: bool = False, wall: bool = True) -> CollisionScene:
    scene = CollisionScene(PANDA, JOINTS, locked={"panda_finger_joint1": 0.02,
                                                  "panda_finger_joint2": 0.02}, exact=exact)
    if wall:
        scene.add_obstacle(WALL)
    return scene


def test_contacts_name_the_link_and_the_obstacle() -> None:
    scene = _scene(wall=False)
    assert not scene.collides(HOME)
    scene.add_obstacle(Obstacle("crate", "box", (0.2, 0.2, 0.2), _pose(0.31, 0.0, 0.49)))
    assert scene.collides(HOME)
    links = {a for a, b in scene.contacts(HOME) if b == "crate"}
    assert links & {"panda_hand", "panda_leftfinger", "panda_rightfinger", "panda_link7"}
    scene.move_obstacle("crate", _pose(0.0, 1.5, 0.1))
    assert not scene.collides(HOME)


def test_direct_move_through_the_wall_is_blocked_and_the_plan_goes_round() -> None:
    scene = _scene()
    assert not scene.collides(LEFT) and not scene.collides(RIGHT)
    assert not scene.segment_free(LEFT, RIGHT, 0.05)
    result = plan(scene, LEFT, RIGHT, np.random.default_rng(7))
    path = result.path
    assert np.allclose(path[0], LEFT) and np.allclose(path[-1], RIGHT)
    assert len(path) >= 3 and result.checks > 0
    exact = _scene(exact=True)
    for a, b in itertools.pairwise(path):
        assert exact.segment_free(a, b, 0.01)
    assert path_length(path) < 10.0


def test_same_seed_same_path() -> None:
    one = plan(_scene(), LEFT, RIGHT, np.random.default_rng(3)).path
    two = plan(_scene(), LEFT, RIGHT, np.random.default_rng(3)).path
    assert len(one) == len(two) and all(np.array_equal(a, b) for a, b in zip(one, two,
                                                                             strict=True))


def test_free_direct_move_is_one_segment() -> None:
    result = plan(_scene(wall=False), LEFT, RIGHT, np.random.default_rng(0))
    assert len(result.path) == 2 and result.samples == 0


def test_start_in_collision_names_what_touches() -> None:
    scene = _scene(wall=False)
    scene.add_obstacle(Obstacle("crate", "box", (0.2, 0.2, 0.2), _pose(0.31, 0.0, 0.49)))
    with pytest.raises(PlanError, match=r"the start is in collision: .*touches crate"):
        plan(scene, HOME, RIGHT, np.random.default_rng(0))


def test_goal_outside_the_limits_is_refused() -> None:
    goal = RIGHT.copy()
    goal[3] = 0.5  # panda_joint4 reaches -0.0698 at most
    with pytest.raises(PlanError, match="goal is outside the joint limits of panda_joint4"):
        plan(_scene(), LEFT, goal, np.random.default_rng(0))


def test_budget_is_a_count_of_checks() -> None:
    with pytest.raises(PlanError, match=r"no path within 40 collision checks .* start tree grew"):
        plan(_scene(), LEFT, RIGHT, np.random.default_rng(0), PlanOptions(max_checks=40))


def test_never_colliding_pairs_leave_out_pairs_that_do_collide() -> None:
    scene = _scene(wall=False)
    quiet = never_colliding_pairs(scene, samples=200, seed=1)
    assert quiet  # many distant links never meet
    assert frozenset(("panda_link0", "panda_link1")) not in quiet  # adjacent: never a pair


class _Band:
    """A plane scene: a disc at (0.5, 0.5) and a band thinner than the check step along the
    first segment of the path, which the checks at 0.05 step over."""

    checks = 0

    def collides(self, q: np.ndarray) -> bool:
        self.checks += 1
        return bool(np.hypot(q[0] - 0.5, q[1] - 0.5) < 0.3
                    or (0.51 < q[0] < 0.53 and abs(q[1]) < 0.02))

    def segment_free(self, a: np.ndarray, b: np.ndarray, step: float) -> bool:
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        return not any(self.collides(a + (b - a) * k / n) for k in range(1, n + 1))


def test_shortcut_never_leaves_a_waypoint_in_collision() -> None:
    # A shortcut starts and ends at points inside segments of the path, between the
    # configurations the segment was checked at: both ends, and the pieces of the segments
    # left in the path, must be checked on their own.
    from bt_manip.manipulation.rrt_connect import shortcut

    scene = _Band()
    path = [np.array([0.0, 0.0]), np.array([1.0, 0.0]), np.array([1.0, 1.0])]
    assert all(scene.segment_free(a, b, 0.05) for a, b in itertools.pairwise(path))
    for seed in range(40):
        out = shortcut(cast(CollisionScene, scene), path, np.random.default_rng(seed),
                       PlanOptions(shortcut_rounds=60))
        assert not any(scene.collides(q) for q in out), seed
        assert all(scene.segment_free(a, b, 0.05) for a, b in itertools.pairwise(out)), seed


def test_the_hulls_hold_the_meshes() -> None:
    # Each configuration is checked on the links' convex hulls first and is free when they
    # are: a hull must contain its mesh, so nothing is nearer to the mesh than to the hull.
    import coal

    scene = _scene(wall=False)
    assert scene.mesh_geometry is not None
    rng = np.random.default_rng(0)
    ball = coal.Sphere(0.01)
    here = coal.Transform3s()
    for hull_obj, mesh_obj in zip(scene.geometry.geometryObjects,
                                  scene.mesh_geometry.geometryObjects, strict=False):
        hull, mesh = hull_obj.geometry, mesh_obj.geometry
        if not isinstance(mesh, coal.BVHModelBase):
            continue
        mesh.computeLocalAABB()
        lo, hi = mesh.aabb_local.min_, mesh.aabb_local.max_
        for _ in range(150):
            at = coal.Transform3s(np.eye(3), rng.uniform(lo - 0.02, hi + 0.02))
            to_hull = coal.distance(hull, here, ball, at, coal.DistanceRequest(),
                                    coal.DistanceResult())
            to_mesh = coal.distance(mesh, here, ball, at, coal.DistanceRequest(),
                                    coal.DistanceResult())
            assert to_hull <= to_mesh + 1e-6, (hull_obj.name, to_hull, to_mesh)


def test_a_stop_callback_ends_the_search() -> None:
    calls = []

    def stop() -> bool:
        calls.append(1)
        return len(calls) > 3

    with pytest.raises(PlanError, match=r"stopped after 3 samples"):
        plan(_scene(), LEFT, RIGHT, np.random.default_rng(7), stop=stop)


class _Plane(_Band):
    """The band's plane as a planning scene for :func:`plan`."""

    lower = np.array([-2.0, -2.0])
    upper = np.array([2.0, 2.0])
    joint_names = ("x", "y")

    def within_limits(self, q: np.ndarray) -> bool:
        return bool(np.all(np.abs(q) <= 2.0))

    def contacts(self, q: np.ndarray) -> list[tuple[str, str]]:
        return [("point", "band")] if self.collides(q) else []


def test_a_direct_move_free_at_the_coarse_step_is_checked_at_the_fine_one() -> None:
    # The straight move steps over the band at 0.05 rad: it is checked again at 0.01 like
    # every other path, and planned round the band.
    scene = _Plane()
    start, goal = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    assert scene.segment_free(start, goal, 0.05) and not scene.segment_free(start, goal, 0.01)
    path = plan(cast(CollisionScene, scene), start, goal, np.random.default_rng(0)).path
    assert np.array_equal(path[0], start) and np.array_equal(path[-1], goal) and len(path) > 2
    assert all(scene.segment_free(a, b, 0.01) for a, b in itertools.pairwise(path))


def test_the_hull_pass_counts_a_hair_gap_as_a_contact() -> None:
    # GJK stopping on its tolerance can report a shallow hull contact as a gap of nanometres:
    # the hull pass asks the meshes below HULL_MARGIN; the meshes' own pass has no margin.
    from bt_manip.manipulation.collision_scene import HULL_MARGIN

    scene = _scene()
    assert all(r.security_margin == HULL_MARGIN for r in scene.gdata.collisionRequests)
    assert all(r.security_margin == 0.0 for r in scene.mesh_gdata.collisionRequests)
    assert all(r.security_margin == 0.0 for r in _scene(exact=True).gdata.collisionRequests)


def _hull_only_point(scene: CollisionScene, q: np.ndarray) -> np.ndarray:
    """A point (root frame) inside a link's convex hull at ``q`` but clear of its mesh by a
    few millimetres: found among seeded samples around the hand."""
    import coal
    import pinocchio as pin

    meshes = scene.mesh_geometry
    assert meshes is not None
    gdata = scene.gdata
    pin.updateGeometryPlacements(scene.model, scene.data, scene.geometry, gdata, q)
    ball, rng = coal.Sphere(0.002), np.random.default_rng(0)
    for index, g in enumerate(scene.geometry.geometryObjects):
        if g.name.startswith("panda_hand") or g.name.startswith("panda_link7"):
            placed = gdata.oMg[index]
            where = coal.Transform3s(placed.rotation, placed.translation)
            hull, mesh = g.geometry, meshes.geometryObjects[index].geometry
            for _ in range(4000):
                p = placed.translation + rng.uniform(-0.12, 0.12, 3)
                at = coal.Transform3s(np.eye(3), p)
                if (coal.distance(hull, where, ball, at, coal.DistanceRequest(),
                                  coal.DistanceResult()) < -0.001
                        and coal.distance(mesh, where, ball, at, coal.DistanceRequest(),
                                          coal.DistanceResult()) > 0.004):
                    return p
    raise AssertionError("no point inside a hull and outside its mesh")


def test_hull_contacts_decide_only_when_asked_and_plans_keep_mesh_answers_at_tight_ends() -> None:
    # A pebble inside the hand's hull but clear of its mesh: the meshes call HOME free, the
    # hull pass alone calls it blocked; a plan from HOME then asks the meshes (its start's
    # hulls touch) and its path is free on the exact meshes.
    scene = _scene(wall=False)
    pebble = _hull_only_point(scene, HOME)
    m = np.eye(4)
    m[:3, 3] = pebble
    scene.add_obstacle(Obstacle("pebble", "sphere", (0.001,), tuple(map(tuple, m))))
    assert not scene.collides(HOME) and scene.hulls_touch(HOME)
    near = HOME + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.02])
    assert scene.segment_free(HOME, near, 0.05)
    assert not scene.segment_free(HOME, near, 0.05, hulls_only=True)
    result = plan(scene, HOME, LEFT, np.random.default_rng(1))
    exact = _scene(exact=True, wall=False)
    exact.add_obstacle(Obstacle("pebble", "sphere", (0.001,), tuple(map(tuple, m))))
    assert all(exact.segment_free(a, b, 0.01) for a, b in itertools.pairwise(result.path))


def test_shortcut_attempts_end_after_the_failures_in_a_row() -> None:
    # Free only along an L of two segments: no shortcut can succeed, so the random attempts
    # (each draws its two points once) stop after ``shortcut_patience`` of them.
    from bt_manip.manipulation.rrt_connect import shortcut

    class _Corridor(_Band):
        def collides(self, q: np.ndarray) -> bool:
            return not (abs(q[1]) < 1e-9 or abs(q[0] - 1.0) < 1e-9)

    class _Counted:
        def __init__(self) -> None:
            self.rng, self.draws = np.random.default_rng(0), 0

        def uniform(self, lo: float, hi: float, size: int) -> np.ndarray:
            self.draws += 1
            return self.rng.uniform(lo, hi, size)

    path = [np.array([0.0, 0.0]), np.array([1.0, 0.0]), np.array([1.0, 1.0])]
    for patience, attempts in ((5, 5), (60, 60)):
        rng = _Counted()
        out = shortcut(cast(CollisionScene, _Corridor()), path, cast(np.random.Generator, rng),
                       PlanOptions(shortcut_rounds=60, shortcut_patience=patience))
        assert len(out) == 3 and all(np.array_equal(a, b) for a, b in zip(out, path,
                                                                            strict=True))
        assert rng.draws == attempts



class _Pocket:
    """A cube of 3 joints, -2..2 rad, with the goal in a hollow box (0.6 rad inside, walls 0.2
    thick) whose only way out is a slot 0.1 x 0.1 in its wall facing the start."""

    checks = 0
    lower, upper = np.full(3, -2.0), np.full(3, 2.0)
    joint_names = ("a", "b", "c")
    centre = np.array([1.0, 0.0, 0.0])

    def _blocked(self, qs: np.ndarray) -> np.ndarray:
        d = np.abs(qs - self.centre)
        far = d.max(axis=-1)
        slot = (qs[..., 0] < 1.0) & (d[..., 1:].max(axis=-1) < 0.05)
        return np.asarray((far >= 0.3) & (far < 0.5) & ~slot)

    def collides(self, q: np.ndarray) -> bool:
        self.checks += 1
        return bool(self._blocked(q))

    def segment_free(self, a: np.ndarray, b: np.ndarray, step: float) -> bool:
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        blocked = self._blocked(a + np.multiply.outer(np.arange(1, n + 1) / n, b - a))
        self.checks += int(np.argmax(blocked)) + 1 if blocked.any() else n
        return not blocked.any()

    def within_limits(self, q: np.ndarray) -> bool:
        return bool(np.all(np.abs(q) <= 2.0))

    def contacts(self, q: np.ndarray) -> list[tuple[str, str]]:
        return [("point", "pocket")] if self.collides(q) else []


def test_a_trapped_goal_tree_gets_the_rounds_and_nearby_targets() -> None:
    # From the pocket, almost every step toward a random point hits its walls: taking turns,
    # the goal tree stays a few nodes while the start tree fills the cube, and most seeds run
    # out of checks. Balanced (the smaller tree extends once the other has three times its
    # nodes), with half its targets near its own nodes, every seed finds the slot.
    start, goal = np.array([-1.5, 0.0, 0.0]), np.array([1.1, 0.15, 0.0])
    plain = PlanOptions(balance=0.0, max_checks=13_000)
    balanced = dataclasses.replace(plain, balance=3.0, balance_from=100, trapped_share=0.5)
    solved_plain = 0
    for seed in range(4):
        try:
            plan(cast(CollisionScene, _Pocket()), start, goal, np.random.default_rng(seed), plain)
            solved_plain += 1
        except PlanError as e:
            assert "no path within" in str(e)
        scene = _Pocket()
        result = plan(cast(CollisionScene, scene), start, goal, np.random.default_rng(seed),
                      balanced)
        assert np.array_equal(result.path[0], start) and np.array_equal(result.path[-1], goal)
        assert all(scene.segment_free(a, b, 0.01) for a, b in itertools.pairwise(result.path))
    assert solved_plain <= 1

"""Navigation: occupancy grid, cost-optimal grid A*, path smoothing, pose planning for long
footprints, and the base controller.

- :mod:`.astar` / :mod:`.astar_search`: ``plan(cost, start, goal)`` on a float32 cost grid.
- :mod:`.shapes`, :mod:`.grid`: collision shapes to ground outlines, outlines to cells, PNG.
- :mod:`.costmap`: clearance, inflation by the footprint and the cost gradient.
- :mod:`.footprint`: the robot's outline, grown by what it carries.
- :mod:`.smoothing`, :mod:`.planner`: shortcuts, world paths and the reasons for no path.
- :mod:`.lattice`: planning over (x, y, heading) when the footprint is long or lopsided;
  :mod:`.outline_check`: whether its outline points keep clear at a pose, a group at a time.
- :mod:`.controller`, :mod:`.segments`: following a path or a pose plan, one tick at a time.
- :mod:`.navigator`: all of it for one robot in one world.
"""

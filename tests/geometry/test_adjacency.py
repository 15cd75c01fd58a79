"""Triangle adjacency for shadow volumes: every edge's neighbour, across welded seams."""

from __future__ import annotations

import numpy as np

from omnirender.geometry.topology import adjacency_indices


def test_a_tetrahedron_sees_each_neighbour_across_each_edge():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    adj = adjacency_indices(v, f).reshape(-1, 6)
    assert np.array_equal(adj[:, 0::2], f)
    for tri, row in zip(f, adj, strict=True):
        for k in range(3):
            a, b, opposite = tri[k], tri[(k + 1) % 3], row[2 * k + 1]
            # the neighbour across a-b holds b, a and the opposite vertex, in its own winding
            assert any(set(other) == {a, b, opposite} for other in f.tolist() if set(other) != set(tri))


def test_duplicated_seam_vertices_are_welded_and_open_borders_point_back():
    # two triangles sharing an edge through duplicated positions (a seam), the rest open
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    f = np.array([[0, 1, 2], [3, 5, 4]])
    adj = adjacency_indices(v, f).reshape(-1, 6)
    assert adj[0, 3] == 5  # across the seam 1-2 lies vertex 5 of the other triangle
    assert adj[0, 1] == 2 and adj[0, 5] == 1  # open borders: the own opposite vertex (a degenerate neighbour)

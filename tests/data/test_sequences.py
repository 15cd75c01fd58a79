"""Tests of omnirender.data: data sequences and as_array."""

import numpy as np
import pytest

from omnirender.data import (
    Array,
    Composite,
    Constant,
    Indexed,
    Repeat,
    Replicate,
    Sequence,
    Skip,
    as_array,
)

SCALARS = np.arange(10) * 10  # 0, 10, ..., 90
VECTORS = np.arange(30, dtype=float).reshape(10, 3)


def from_iter(seq):
    """The sequence built element by element through iteration."""
    items = list(seq)
    return np.array(items, dtype=seq.dtype).reshape((len(items), *seq.shape))


def from_getitem(seq):
    items = [seq[i] for i in range(len(seq))]
    return np.array(items, dtype=seq.dtype).reshape((len(items), *seq.shape))


def check(seq, expected=None):
    """array(), iteration and indexing agree (and with ``expected``)."""
    a = seq.array()
    assert isinstance(a, np.ndarray)
    assert a.shape == (len(seq), *seq.shape)
    assert a.dtype == seq.dtype
    np.testing.assert_array_equal(a, from_iter(seq))
    np.testing.assert_array_equal(a, from_getitem(seq))
    if len(seq):
        np.testing.assert_array_equal(seq[-1], a[-1])
        np.testing.assert_array_equal(seq[-len(seq)], a[0])
    if expected is not None:
        np.testing.assert_array_equal(a, np.asarray(expected))
    return a


# --------------------------------------------------------------------------
# semantics with the examples of the issue


def test_replicate_string():
    seq = Replicate("abcd", 3)
    assert "".join(seq) == "aaabbbcccddd"
    assert len(seq) == 12
    assert "".join(seq.array()) == "aaabbbcccddd"
    check(seq, list("aaabbbcccddd"))


def test_repeat_string():
    seq = Repeat("abcde", 1, 4, 4)
    assert "".join(seq) == "bcdbcdbcdbcd"
    assert len(seq) == 12
    check(seq, list("bcdbcdbcdbcd"))


def test_repeat_defaults_whole_source_once():
    assert "".join(Repeat("abc")) == "abc"
    assert "".join(Repeat("abc", times=2)) == "abcabc"
    assert "".join(Repeat("abcde", 2)) == "cde"


def test_skip_string():
    seq = Skip("abcdefghij", 3)
    assert "".join(seq) == "abdeghj"
    assert len(seq) == 7
    check(seq, list("abdeghj"))


def test_skip_every_one_drops_everything():
    seq = Skip("abcdef", 1)
    assert len(seq) == 0
    assert list(seq) == []
    check(seq)


def test_skip_every_larger_than_source_keeps_everything():
    assert "".join(Skip("abc", 5)) == "abc"
    assert "".join(Skip("abc", 3)) == "ab"


def test_indexed_string():
    seq = Indexed([2, 0, 0, 4, 1], "abcde")
    assert "".join(seq) == "caaeb"
    check(seq, list("caaeb"))


def test_composite_string():
    seq = Composite("ab", "", "cde", Replicate("f", 2))
    assert "".join(seq) == "abcdeff"
    assert len(seq) == 7
    check(seq, list("abcdeff"))


def test_constant():
    seq = Constant(7, 4)
    assert list(seq) == [7, 7, 7, 7]
    check(seq, [7, 7, 7, 7])
    assert "".join(Constant("x", 3)) == "xxx"
    assert "".join(Constant("xy", 2)) == "xyxy"  # a string value is one element


def test_constant_vector_is_read_only_view():
    seq = Constant((0.0, 0.0, 1.0), 5)
    assert seq.shape == (3,)
    a = check(seq, [[0, 0, 1]] * 5)
    assert not a.flags.writeable
    assert a.strides[0] == 0  # broadcast: one value in memory


def test_array_is_no_copy():
    a = np.arange(12.0).reshape(4, 3)
    seq = Array(a)
    assert seq.array() is a
    assert np.shares_memory(seq.array(), a)
    assert np.shares_memory(seq[1], a)
    assert seq.shape == (3,)
    assert seq.dtype == a.dtype
    assert len(seq) == 4
    check(seq, a)


def test_array_from_array_likes():
    check(Array([1, 2, 3]), [1, 2, 3])
    check(Array(((1, 2), (3, 4))), [[1, 2], [3, 4]])
    seq = Array("hey")
    assert seq.dtype == np.dtype("<U1")
    assert "".join(seq) == "hey"
    # a list of strings is a sequence of strings, not of characters
    assert list(Array(["ab", "c"])) == ["ab", "c"]


def test_views_where_possible():
    a = np.arange(10)
    assert np.shares_memory(Repeat(a, 2, 7, 1).array(), a)
    assert Replicate(a, 1).array() is a
    assert Skip(a, 11).array() is a
    assert Composite(a).array() is a


# --------------------------------------------------------------------------
# scalar and vector data, every class


def all_sequences(data):
    n = len(data)
    return [
        Array(data),
        Constant(data[0], 4),
        Constant(data[0], 0),
        Replicate(data, 3),
        Replicate(data, 0),
        Repeat(data, 2, 5, 3),
        Repeat(data, 3, 3, 2),
        Repeat(data, 0, n, 0),
        Skip(data, 3),
        Skip(data, 1),
        Skip(data, 2),
        Indexed([9, 0, 3, 3, 1], data),
        Indexed([], data),
        Composite(data, data[:2], data[5:5]),
    ]


@pytest.mark.parametrize("data", [SCALARS, VECTORS], ids=["scalar", "vector"])
def test_array_equals_iteration(data):
    for seq in all_sequences(data):
        assert seq.shape == data.shape[1:], seq
        check(seq)


def test_vector_elements_are_rows():
    seq = Replicate(VECTORS, 2)
    assert seq.shape == (3,)
    np.testing.assert_array_equal(seq[0], VECTORS[0])
    np.testing.assert_array_equal(seq[3], VECTORS[1])
    np.testing.assert_array_equal(seq[-1], VECTORS[-1])
    assert all(len(row) == 3 for row in seq)


def test_semantics_against_python_lists():
    data = list(range(10))
    assert list(Replicate(data, 2))[:5] == [0, 0, 1, 1, 2]
    assert list(Repeat(data, 7, 10, 2)) == [7, 8, 9, 7, 8, 9]
    assert list(Skip(data, 4)) == [0, 1, 2, 4, 5, 6, 8, 9]
    assert list(Indexed([3, 1], data)) == [3, 1]
    assert list(Composite([1], (2, 3))) == [1, 2, 3]


def test_nested_sequences():
    comp = Composite("abc", Replicate("xy", 2))  # abcxxyy
    rep = Repeat(comp, 2, 6, 2)  # cxxy cxxy
    seq = Indexed([7, 0, 3, 4], rep)  # y c y c
    assert "".join(seq) == "ycyc"
    check(seq, list("ycyc"))
    skip = Skip(Composite(rep, Constant("z", 2)), 2)  # cxxycxxyzz -> cxcxz
    assert "".join(skip) == "cxcxz"
    check(skip)


def test_nested_vectors():
    base = Composite(VECTORS[:4], Constant((-1.0, -2.0, -3.0), 2))
    seq = Indexed(Repeat([5, 0], times=3), Replicate(base, 2))
    expected = np.repeat(base.array(), 2, axis=0)[[5, 0] * 3]
    check(seq, expected)
    # indices given as a sequence
    assert seq.indices.tolist() == [5, 0] * 3


def test_len_and_indexing():
    seq = Replicate([1, 2], 3)
    assert len(seq) == 6
    assert seq[0] == 1 and seq[5] == 2 and seq[-1] == 2 and seq[-6] == 1
    assert seq[np.int64(3)] == 2
    with pytest.raises(IndexError, match="out of range"):
        seq[6]
    with pytest.raises(IndexError, match="out of range"):
        seq[-7]
    with pytest.raises(TypeError, match="integers"):
        seq[1.0]
    with pytest.raises(IndexError):
        Skip("abc", 1)[0]


def test_is_sequence_and_numpy_interop():
    seqs = all_sequences(VECTORS)
    for seq in seqs:
        assert isinstance(seq, Sequence)
        np.testing.assert_array_equal(np.asarray(seq), seq.array())
    np.testing.assert_array_equal(np.asarray(Replicate([1, 2], 2), dtype=float), [1.0, 1.0, 2.0, 2.0])
    with pytest.raises(TypeError):
        Sequence()


def test_parameters_are_exposed():
    r = Repeat("abcde", 1, 4, 4)
    assert (r.start, r.stop, r.times) == (1, 4, 4)
    assert isinstance(r.source, Array)
    assert Replicate("ab", 2).times == 2
    assert Skip("ab", 2).every == 2
    assert len(Composite("a", "b").sources) == 2
    assert "Repeat" in repr(r)


def test_slots():
    for seq in all_sequences(SCALARS):
        with pytest.raises(AttributeError):
            seq.foo = 1


def test_indices_copied_and_read_only():
    idx = np.array([0, 1, 2])
    seq = Indexed(idx, "abc")
    idx[0] = 99  # cannot invalidate the validated copy
    assert "".join(seq) == "abc"
    assert not seq.indices.flags.writeable


def test_composite_dtype_promotion():
    seq = Composite([1, 2], [0.5])
    assert seq.dtype == np.float64
    check(seq, [1.0, 2.0, 0.5])
    assert Composite("a", ["bcd"]).dtype == np.dtype("<U3")


# --------------------------------------------------------------------------
# as_array


def test_as_array():
    a = np.arange(6.0).reshape(2, 3)
    assert as_array(a) is a
    assert as_array(a, float) is a
    assert as_array(Array(a)) is a
    np.testing.assert_array_equal(as_array(Replicate([1, 2], 2)), [1, 1, 2, 2])
    np.testing.assert_array_equal(as_array([[1, 2, 3]], np.float32), [[1, 2, 3]])
    assert as_array([1, 2], np.float32).dtype == np.float32
    assert list(as_array("ab")) == ["a", "b"]


def test_as_array_errors_name_the_value():
    with pytest.raises(ValueError, match="vertices is not a regular array"):
        as_array([[1, 2, 3], [4, 5]], name="vertices")
    with pytest.raises(ValueError, match="vertices cannot be converted to float64"):
        as_array(["a", "b"], float, name="vertices")


# --------------------------------------------------------------------------
# invalid parameters


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Array(5), "Array: data must be a sequence"),
        (lambda: Array([[1, 2], [3]]), "Array: data is not a regular array"),
        (lambda: Constant(1, -1), "Constant: count must be >= 0, got -1"),
        (lambda: Constant(1, 2.5), "Constant: count must be an integer"),
        (lambda: Constant([[1], [2, 3]], 2), "Constant: value is not a regular"),
        (lambda: Replicate("ab", -2), "Replicate: times must be >= 0, got -2"),
        (lambda: Replicate("ab", True), "Replicate: times must be an integer"),
        (lambda: Replicate(3, 2), "Replicate: source must be a sequence"),
        (lambda: Replicate([(1, 2), (3,)], 2), "Replicate: source is not a regular"),
        (lambda: Repeat("abc", -1, 2, 1), "Repeat: start must be >= 0, got -1"),
        (lambda: Repeat("abc", 0, -1, 1), "Repeat: stop must be >= 0, got -1"),
        (lambda: Repeat("abc", 0, 4, 1), "Repeat: stop = 4 is out of range"),
        (lambda: Repeat("abc", 2, 1, 1), "Repeat: start = 2 must not exceed stop"),
        (lambda: Repeat("abc", 0, 3, -1), "Repeat: times must be >= 0, got -1"),
        (lambda: Repeat("abc", "0", 3, 1), "Repeat: start must be an integer"),
        (lambda: Skip("abc", 0), "Skip: every must be >= 1, got 0"),
        (lambda: Skip("abc", -3), "Skip: every must be >= 1, got -3"),
        (lambda: Skip([[1], [2, 3]], 2), "Skip: source is not a regular"),
        (
            lambda: Indexed([0, 1, 2, 7], "abcde"),
            r"Indexed: indices\[3\] = 7 is out of range for a source of length 5",
        ),
        (
            lambda: Indexed([0, -1], "abcde"),
            r"Indexed: indices\[1\] = -1 is out of range for a source of length 5",
        ),
        (lambda: Indexed([0.0, 1.0], "abc"), "Indexed: indices must be integers"),
        (lambda: Indexed([True], "abc"), "Indexed: indices must be integers"),
        (lambda: Indexed([[0, 1]], "abc"), "Indexed: indices must be 1-D"),
        (lambda: Indexed([[0, 1], [2]], "abc"), "Indexed: indices is not a regular"),
        (lambda: Indexed([0], [[1, 2], [3]]), "Indexed: source is not a regular"),
        (lambda: Composite(), "Composite: sources must not be empty"),
        (
            lambda: Composite(VECTORS, [[1, 2]]),
            r"Composite: sources\[1\] has element shape \(2,\), expected \(3,\)",
        ),
        (
            lambda: Composite([1, 2], [3], [[4]]),
            r"Composite: sources\[2\] has element shape \(1,\)",
        ),
        (lambda: Composite("ab", [1]), r"Composite: sources\[1\] has dtype int64"),
        (lambda: Composite("a", [[1], [2, 3]]), r"Composite: sources\[1\] is not a"),
    ],
)
def test_invalid_parameters(make, message):
    with pytest.raises(ValueError, match=message):
        make()


# --------------------------------------------------------------------------
# property test: random trees of sequences, without hypothesis


def _random_sequence(rng, depth, width):
    """A random sequence tree over data of element shape ``(width,)`` or ()."""
    shape = (width,) if width else ()
    kind = rng.integers(0, 7) if depth > 0 else rng.integers(0, 2)
    if kind == 0:
        n = int(rng.integers(0, 8))
        return Array(rng.integers(-50, 50, size=(n, *shape)))
    if kind == 1:
        return Constant(rng.integers(-50, 50, size=shape), int(rng.integers(0, 5)))
    src = _random_sequence(rng, depth - 1, width)
    n = len(src)
    if kind == 2:
        return Replicate(src, int(rng.integers(0, 4)))
    if kind == 3:
        start = int(rng.integers(0, n + 1))
        stop = int(rng.integers(start, n + 1))
        return Repeat(src, start, stop, int(rng.integers(0, 4)))
    if kind == 4:
        return Skip(src, int(rng.integers(1, 5)))
    if kind == 5:
        k = int(rng.integers(0, 10))
        idx = rng.integers(0, n, size=k) if n else np.empty(0, dtype=int)
        return Indexed(idx, src)
    parts = [src] + [_random_sequence(rng, depth - 1, width) for _ in range(rng.integers(0, 3))]
    return Composite(*parts)


def _reference(seq):
    """Plain-Python semantics, independent of the implementation."""
    if isinstance(seq, Array):
        return list(seq.array())
    if isinstance(seq, Constant):
        return [seq.value] * len(seq)
    if isinstance(seq, Replicate):
        return [x for x in _reference(seq.source) for _ in range(seq.times)]
    if isinstance(seq, Repeat):
        return _reference(seq.source)[seq.start : seq.stop] * seq.times
    if isinstance(seq, Skip):
        src = _reference(seq.source)
        return [x for k, x in enumerate(src, 1) if k % seq.every != 0]
    if isinstance(seq, Indexed):
        src = _reference(seq.source)
        return [src[i] for i in seq.indices]
    if isinstance(seq, Composite):
        return [x for s in seq.sources for x in _reference(s)]
    raise AssertionError(seq)


def test_random_trees_agree():
    rng = np.random.default_rng(0)
    for _ in range(500):
        width = int(rng.choice([0, 3]))
        seq = _random_sequence(rng, int(rng.integers(0, 5)), width)
        a = check(seq)
        ref = _reference(seq)
        assert len(ref) == len(seq)
        expected = np.array(ref, dtype=seq.dtype).reshape(a.shape)
        np.testing.assert_array_equal(a, expected)

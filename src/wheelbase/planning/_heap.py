"""A binary min-heap of ``(key, item)`` pairs in two arrays, for the Numba search kernels.

Numba's ``heapq`` on a list of tuples costs atomic reference counts at every push and pop (a
quarter of Hybrid A*'s time); these inline functions touch plain arrays only. The order is the
tuples' (key first, then item), so a search pops exactly what ``heapq`` would. Room for a push
is the caller's job.
"""

from __future__ import annotations

import numba

__all__: list[str] = []


@numba.njit(cache=True, inline="always")
def _before(ka, ia, kb, ib):
    """Tuple order of (key, node) entries."""
    return ka < kb or (ka == kb and ia < ib)


@numba.njit(cache=True, inline="always")
def _heap_push(keys, ids, size, key, item):
    """Push onto the binary heap ``keys[:size]``/``ids[:size]`` (room for one more is the
    caller's job); returns the new size."""
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        if not _before(key, item, keys[parent], ids[parent]):
            break
        keys[i] = keys[parent]
        ids[i] = ids[parent]
        i = parent
    keys[i] = key
    ids[i] = item
    return size + 1


@numba.njit(cache=True, inline="always")
def _heap_pop(keys, ids, size):
    """Pop the least entry of a non-empty heap: ``(key, node, new size)``."""
    key, item = keys[0], ids[0]
    size -= 1
    if size > 0:
        lk, li = keys[size], ids[size]
        i = 0
        while True:
            c = 2 * i + 1
            if c >= size:
                break
            if c + 1 < size and _before(keys[c + 1], ids[c + 1], keys[c], ids[c]):
                c += 1
            if not _before(keys[c], ids[c], lk, li):
                break
            keys[i] = keys[c]
            ids[i] = ids[c]
            i = c
        keys[i] = lk
        ids[i] = li
    return key, item, size

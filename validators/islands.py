"""Islands of a sliced layer (numpy, scipy.ndimage; shares no code with lamina), for the SL1
validators: the 8-connected regions of a layer's lit pixels none of whose pixels is lit in the
layer below.

Only pixels lit here and not below can make one, so the regions are labelled within the box
of those pixels (one pixel wider), not over the whole display: a region of them touching a
pixel lit in both layers is part of a region that stands on the layer below; one that touches
none is a whole region of the layer (its lit neighbours are all new too), an island.
"""
import numpy as np
from scipy import ndimage

EIGHT = np.ones((3, 3), dtype=bool)


def unheld(lit, below):
    """The islands of boolean layer `lit` over `below`: (r0, c0, labels, keep), the labels
    (8-connected, scipy's raster order) of the new pixels in the box at row r0, column c0, and
    which labels are islands (`keep[label]`); None when no pixel is lit without one below."""
    new = lit & ~below
    rows = np.flatnonzero(new.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(new.any(axis=0))
    r0, r1 = max(rows[0] - 1, 0), min(rows[-1] + 2, lit.shape[0])
    c0, c1 = max(cols[0] - 1, 0), min(cols[-1] + 2, lit.shape[1])
    labels, count = ndimage.label(new[r0:r1, c0:c1], structure=EIGHT)
    touched = dilated(lit[r0:r1, c0:c1] & below[r0:r1, c0:c1])
    keep = np.ones(count + 1, dtype=bool)
    keep[labels[touched]] = False
    keep[0] = False
    return r0, c0, labels, keep


def dilated(mask):
    """`mask` grown by one pixel to its 8 neighbours in its last two axes (each layer of a
    stack on its own): the 3 × 3 square, along rows then along columns."""
    out = mask.copy()
    out[..., 1:, :] |= mask[..., :-1, :]
    out[..., :-1, :] |= mask[..., 1:, :]
    rows = out.copy()
    out[..., 1:] |= rows[..., :-1]
    out[..., :-1] |= rows[..., 1:]
    return out


def island_sizes(lit, below):
    """Pixel counts of the islands of `lit` over `below`, in scipy's label order."""
    found = unheld(lit, below)
    if found is None:
        return []
    _, _, labels, keep = found
    sizes = np.bincount(labels.ravel(), minlength=keep.size)
    return [int(sizes[c]) for c in np.flatnonzero(keep)]


def island_mask(lit, below):
    """The pixels of `lit` in its islands over `below`."""
    out = np.zeros_like(lit)
    found = unheld(lit, below)
    if found is not None:
        r0, c0, labels, keep = found
        out[r0:r0 + labels.shape[0], c0:c0 + labels.shape[1]] = keep[labels]
    return out

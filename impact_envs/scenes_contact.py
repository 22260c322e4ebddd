"""The finger-hammer contact of the authors' HammerBasket MJCF, as an alternative to ours
(issue 55 item 6; ``../shared/reference/authors_impact.md``, scene facts).

Our scene (``assets/hammer_basket_scene.xml``) sets explicit finger-pad/hammer ``<pair>``s with
friction and condim only, so MuJoCo's pair defaults apply (solref 0.02 1, solimp 0.9 0.95
0.001), and ``common.xml`` sets ``noslip_iterations`` 1. Theirs has no pairs: the geoms'
values are mixed (equal ``solmix``: their mean) from the finger (solref 0.0005 1, solimp 0.999
0.9999) and the hammer (0.002 1 / 0.95 0.99), and no noslip. ``use_their_finger_contact``
rewrites a compiled model in place; ``HammerBasket-v1`` itself keeps ours (a change of
behaviour belongs to a new env version).
"""

from __future__ import annotations

import numpy as np

from impact_control.errors import InvalidArgumentError

FINGER_SOLREF = (0.0005, 1.0)
FINGER_SOLIMP = (0.999, 0.9999, 0.001)
HAMMER_SOLREF = (0.002, 1.0)
HAMMER_SOLIMP = (0.95, 0.99, 0.001)
THEIR_PAIR_SOLREF = tuple(np.mean([FINGER_SOLREF, HAMMER_SOLREF], axis=0).tolist())
"""Their mixed finger-hammer solref [s, -]: 0.00125 1."""
THEIR_PAIR_SOLIMP = tuple(np.mean([FINGER_SOLIMP, HAMMER_SOLIMP], axis=0).tolist())
"""Their mixed finger-hammer solimp: 0.9745 0.99495 0.001."""
CONTACTS = ("ours", "theirs")


def finger_hammer_pairs(model) -> list[int]:
    """Indices of the model's explicit pairs between a finger pad and a hammer geom."""
    names = [model.body(i).name for i in range(model.nbody)]
    if "hammer" not in names:
        return []
    hammer = names.index("hammer")
    out = []
    for p in range(model.npair):
        a, b = model.pair_geom1[p], model.pair_geom2[p]
        names = (model.geom(a).name, model.geom(b).name)
        on_hammer = hammer in (model.geom_bodyid[a], model.geom_bodyid[b])
        if on_hammer and any("pad" in n for n in names):
            out.append(p)
    return out


def use_their_finger_contact(model) -> None:
    """Set the finger-hammer pairs to their mixed solref / solimp and noslip off, in place.

    Raises:
        InvalidArgumentError: the model has no finger-pad/hammer pair to change.
    """
    pairs = finger_hammer_pairs(model)
    if not pairs:
        raise InvalidArgumentError("this model has no finger-pad/hammer contact pair; valid: "
                                   "IMPACT/HammerBasket-v1's scene")
    model.pair_solref[pairs] = THEIR_PAIR_SOLREF
    model.pair_solimp[pairs, :3] = THEIR_PAIR_SOLIMP
    model.opt.noslip_iterations = 0

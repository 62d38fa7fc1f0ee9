"""More articulated models: further sizes of the families of :mod:`gendex_envs.assets.articulated` whose every
mechanism the solver already works (a lid lifted open and pressed shut, a door pushed shut, a drawer pushed in, a
laptop's screen folded down), so each new model is opened and closed by the skills measured on its siblings.

A model here follows the conventions of :mod:`gendex_envs.assets.articulated` (front at -x, positive joint values
open). Sizes are of real products: a 35 cm kitchen step bin, a 29 cm shoe-box-sized storage box, a 14-inch laptop,
a 1.2 cu ft microwave, a two-drawer chest 52 cm wide (at 36 cm tall its top drawer, pulled out, stood in the
resting hand: the critic's penetration check refused it three times, so it is as tall as the narrow one).

``python -m gendex_envs.assets.build_articulated`` writes every model of :func:`all_models`.
"""

from __future__ import annotations

from collections.abc import Callable

from gendex_envs.assets.articulated import (
    VARIANTS,
    Model,
    box_with_lid,
    cabinet,
    drawer_chest,
    laptop,
    microwave,
    trash_can,
)

MORE_VARIANTS: dict[str, Callable[[], Model]] = {
    "trash_can_medium": lambda: trash_can("trash_can_medium", 0.23, 0.27, 0.35),
    "box_with_lid_medium": lambda: box_with_lid("box_with_lid_medium", 0.21, 0.29, 0.13, 0.008, (0.5, 0.15)),
    "laptop_14in": lambda: laptop("laptop_14in", 0.225, 0.32, 0.018),
    "microwave_large": lambda: microwave("microwave_large", 0.38, 0.52, 0.31, 0.12),
    "drawer_chest_2_wide": lambda: drawer_chest("drawer_chest_2_wide", 2, 0.40, 0.52, 0.40),
    "cabinet_tall": lambda: cabinet("cabinet_tall", "left", 0.40, 0.42, 0.62),
}
"""The models of this module, by asset id."""


def all_models() -> list[Model]:
    """Every shipped articulated model (:data:`~gendex_envs.assets.articulated.VARIANTS` and
    :data:`MORE_VARIANTS`), sorted by id."""
    clash = sorted(set(VARIANTS) & set(MORE_VARIANTS))
    if clash:
        raise ValueError(f"articulated model ids defined twice: {clash}")
    return [make() for _, make in sorted({**VARIANTS, **MORE_VARIANTS}.items())]

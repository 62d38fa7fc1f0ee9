"""How the offline author words a task: varied instructions that still say exactly what the task is.

A task grammar that writes every "put X into Y" as the same sentence gives a library whose instructions an embedding
model cannot tell apart (the library of 20 such tasks measured a mean pairwise MiniLM cosine of 0.41; GenDexHand
reports 0.288, RoboGen 0.191). People ask for the same thing in many ways, and often say why. :func:`phrase` words a
task from four seeded choices:

- a **command** template of the task's skill (several verbs and sentence shapes per skill, each one a faithful
  statement of what success needs: *into* for a container, *onto* for a plate, *without picking it up* for a push);
- the **names** of its objects, drawn from the words a person would use for that catalog category (the same
  synonyms :mod:`generator.instruction` reads back: *cupboard*, *tap*, *bin*, *dresser*);
- an optional **situation** before the command and an optional **purpose** after it, both from pools keyed by what
  the main object is (fruit, packaged food, a ball, a toy, a tool, kitchenware, furniture, an appliance ...) and,
  for a part that opens or closes something, by which (:data:`SITUATIONS_DIRECTED`, :data:`PURPOSES_DIRECTED`).
  They say why someone would want the task done; they never add a condition the task does not check.

The choice is a pure function of the ``rng`` given, so a seeded author words the same task the same way; or, with a
``choose`` function, the framing is picked from every one the command allows (:func:`framings`; the least like a
library's instructions: :mod:`generator.reword`). :func:`split` takes a written instruction apart again.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from generator.command_templates import COMMANDS, PLACE_AT

NAMES: dict[str, tuple[str, ...]] = {
    "peg_holder": ("peg holder", "holder", "pegboard"),
    "spill": ("spill", "stain", "mess"),
    "mug_hook": ("mug hook", "hook", "cup hook"),
    "mug_tree": ("mug tree", "mug stand"),
    "mug_rack": ("mug rack", "wall rack"),
    "bowl": ("bowl", "serving bowl", "mixing bowl"),
    "pot": ("pot", "cooking pot", "saucepan"),
    "plate": ("plate", "dinner plate", "dish"),
    "mug": ("mug", "coffee mug"),
    "cup": ("cup", "teacup"),
    "can": ("can", "tin can", "soup can"),
    "tuna_can": ("tuna can", "tin of tuna"),
    "block": ("block", "toy block", "cube"),
    "foam_brick": ("foam brick", "soft brick"),
    "rubiks_cube": ("rubik's cube", "puzzle cube"),
    "toy_duck": ("toy duck", "rubber duck"),
    "mustard_bottle": ("mustard bottle", "bottle of mustard"),
    "marker": ("marker", "felt pen"),
    "cabinet": ("cabinet", "cupboard"),
    "microwave": ("microwave", "microwave oven"),
    "drawer_chest": ("chest of drawers", "dresser", "drawer unit"),
    "trash_can": ("trash can", "bin", "waste bin"),
    "box_with_lid": ("lidded box", "storage box"),  # not "box with a lid": "the box with a lid lid"
    "faucet": ("faucet", "tap", "mixer tap"),
    "refrigerator": ("fridge", "refrigerator"),
    "laptop": ("laptop", "notebook computer"),
    "knob": ("knob", "dial"),
    "cutting_board": ("cutting board", "chopping board"),
    "tray": ("tray", "serving tray"),
    "valve": ("valve", "ball valve", "shutoff valve"),
    "tumbler": ("tumbler", "drinking glass", "water glass"),
    "beaker": ("beaker", "lab beaker", "measuring beaker"),
    "paper_cup": ("paper cup", "disposable cup", "takeaway cup"),
    "sugar_box": ("sugar box", "box of sugar"),
    "pudding_box": ("pudding box", "box of pudding"),
    "cracker_box": ("cracker box", "box of crackers"),
    "gelatin_box": ("gelatin box", "box of gelatin", "jelly box"),
    "sponge": ("sponge", "kitchen sponge", "dish sponge"),
    "pitcher": ("pitcher", "jug"),
    "oven": ("oven", "stove oven"),
    "dishwasher": ("dishwasher", "dish washer"),
    "dice": ("dice", "die"),
    "wine_glass": ("wine glass", "wineglass"),
    "kiwi": ("kiwi", "kiwi fruit"),
    "bell_pepper": ("bell pepper", "sweet pepper"),
    "salt_shaker": ("salt shaker", "salt cellar"),
    "pepper_mill": ("pepper mill", "pepper grinder"),
    "yogurt_cup": ("yogurt cup", "yoghurt cup"),
    "milk_carton": ("milk carton", "carton of milk"),
    "juice_box": ("juice box", "juice carton"),
    "shampoo_bottle": ("shampoo bottle", "bottle of shampoo"),
    "toothpaste_tube": ("tube of toothpaste", "toothpaste tube"),
    "soap_bar": ("bar of soap", "soap bar"),
    "service_bell": ("service bell", "desk bell"),
    "flashlight": ("flashlight", "torch"),
    "tape_roll": ("roll of tape", "tape roll", "roll of duct tape"),
    "pool_ball": ("pool ball", "billiard ball"),
    "rubber_ball": ("rubber ball", "bouncy ball"),
    "chess_king": ("chess king", "king"),
    "chess_rook": ("chess rook", "rook"),
    "toy_car": ("toy car", "model car"),
    "teddy_bear": ("teddy bear", "teddy"),
    "basket": ("basket", "wicker basket"),
    "baking_dish": ("baking dish", "casserole dish", "oven dish"),
    "storage_bin": ("storage bin", "plastic bin", "crate"),
    "placemat": ("placemat", "place mat", "table mat"),
    "baking_sheet": ("baking sheet", "baking tray", "sheet pan"),
    "soda_can": ("soda can", "can of soda", "drinks can"),
    "pepper_shaker": ("pepper shaker", "pepper pot"),
    "zucchini": ("zucchini", "courgette"),
    "eggplant": ("eggplant", "aubergine"),
    "corn": ("corn cob", "ear of corn"),
    "ketchup_bottle": ("ketchup bottle", "bottle of ketchup"),
    "honey_jar": ("honey jar", "jar of honey"),
    "olive_oil_bottle": ("olive oil bottle", "bottle of olive oil"),
    "beer_bottle": ("beer bottle", "bottle of beer"),
    "ice_cream_tub": ("ice cream tub", "tub of ice cream"),
    "tea_tin": ("tea tin", "tea caddy"),
    "butter": ("block of butter", "butter"),
    "cereal_box": ("cereal box", "box of cereal"),
    "cheese": ("wedge of cheese", "cheese"),
    "bread_roll": ("bread roll", "bun"),
    "donut": ("donut", "doughnut"),
    "chess_pawn": ("chess pawn", "pawn"),
    "chess_bishop": ("chess bishop", "bishop"),
    "chess_queen": ("chess queen", "queen"),
    "chess_knight": ("chess knight", "knight"),
    "bowling_pin": ("bowling pin", "skittle"),
    "letter_block": ("letter block", "alphabet block"),
    "piggy_bank": ("piggy bank", "money box"),
    "lotion_bottle": ("lotion bottle", "bottle of lotion"),
    "tissue_box": ("tissue box", "box of tissues"),
    "perfume_bottle": ("perfume bottle", "bottle of perfume"),
    "toilet_roll": ("toilet roll", "roll of toilet paper"),
    "glue_bottle": ("glue bottle", "bottle of glue"),
    "light_bulb": ("light bulb", "bulb"),
    "hourglass": ("hourglass", "sand timer"),
    "paint_can": ("paint can", "tin of paint"),
    "flower_pot": ("flower pot", "plant pot"),
}
"""Words for a catalog category (default: the category with spaces); every one is read back to that category by
:mod:`generator.instruction`."""

MODEL_WORDS: dict[str, str] = {
    "cabinet_left_hinge": "left-hinged", "cabinet_right_hinge": "right-hinged",
    "refrigerator_left_hinge": "left-hinged", "refrigerator_right_hinge": "right-hinged",
    "microwave_compact": "compact", "microwave_standard": "standard", "oven_compact": "compact",
    "oven_standard": "standard", "drawer_chest_1": "single-drawer", "drawer_chest_2": "two-drawer",
    "drawer_chest_3": "three-drawer", "trash_can_small": "small", "trash_can_tall": "tall",
    "box_with_lid_small": "small", "box_with_lid_large": "large", "laptop_13in": "13-inch", "laptop_15in": "15-inch",
    "trash_can_medium": "medium", "box_with_lid_medium": "medium", "laptop_14in": "14-inch",
    "microwave_large": "large", "drawer_chest_2_wide": "wide", "cabinet_tall": "tall",
    "dishwasher_plain": "plain", "dishwasher_rack": "racked",
    "peg_round": "round", "peg_square": "square", "peg_thin": "thin",
    "spill_round": "round", "spill_square": "square", "spill_long": "long",
}
"""Words that tell a model from its siblings (articulated models, pegs), read back by :mod:`generator.instruction` as
that model: two tasks on sibling models must not read alike."""

PIECE_NAMES: dict[str, tuple[str, ...]] = {"bead": ("beads", "ceramic beads", "pellets"),
                                           "marble": ("marbles", "glass marbles")}
"""Words for the loose pieces a vessel pours (plural: there are a dozen), read back as that piece."""

SURFACES = ("table", "tabletop", "counter", "worktop")

Chooser = Callable[[list[str]], str]
"""Picks one sentence of those the author could write for a task."""

SITUATIONS: dict[str, tuple[str, ...]] = {
    "fruit": ("Breakfast is being laid out for a family of four", "The grocery bag was tipped out onto the {s}",
              "A guest who just ran a marathon asked for something fresh",
              "The fruit salad for the school fair is one piece short", "Market day left produce everywhere",
              "The nutritionist wants every snack weighed and logged", "A still-life painter is arranging a scene",
              "The smoothie blender is already humming", "Grandma is making jam this afternoon",
              "The orchard tour ends with a tasting", "Harvest festival decorations go up at noon",
              "A vegan cookery workshop starts shortly", "The greengrocer's van has just unloaded",
              "Tomorrow's packed lunch needs something sweet"),
    "food": ("The pantry shelf is being restocked after the delivery", "Tonight's curry recipe is being gathered",
             "The food bank volunteers are sorting donations", "Lunch boxes are being packed for the school trip",
             "The camping trip leaves at dawn", "A stock-take of the corner shop is under way",
             "The cooking show goes live in ten minutes", "The student flat's shelves are nearly empty",
             "A charity bake sale needs ingredients counted", "The hiking club is packing provisions",
             "Supper for the night shift is being prepared", "The shopping list has been ticked off twice"),
    "ball": ("Playtime in the garden has ended and it is getting dark", "The sports bag is being packed for Saturday",
             "Tennis practice at the club is over", "The puppy keeps chasing anything that rolls",
             "The PE teacher is counting equipment after class", "A rainy afternoon moved the games indoors",
             "The juggling lesson has just finished", "Summer camp's equipment shed gets inspected today",
             "The neighbours' children left their games behind", "A coach is setting up drills for the under-tens",
             "The caretaker is locking the gym for the holidays"),
    "toy": ("The playroom floor must be clear by bedtime", "A toddler is learning shapes and colours",
            "The nursery is being tidied before the parents arrive", "Game night starts in five minutes",
            "The kindergarten teacher is setting up a counting lesson", "A toy shop window display is being built",
            "Grandchildren are visiting this weekend", "The babysitter is tidying after a long afternoon",
            "A birthday party for a four-year-old is winding down", "The charity shop is pricing donated games",
            "The museum of childhood is rearranging an exhibit"),
    "tool": ("The workbench is being cleared after fixing the bicycle", "A carpenter needs a hand in the workshop",
             "The art class is packing up for the weekend",
             "The garage sale opens in an hour", "The repair café has a queue of broken lamps",
             "The shed roof is being patched before the storm", "A model railway is being rebuilt in the loft",
             "The sculptor's studio gets swept on Fridays", "A volunteer is mending fences at the allotment"),
    "kitchenware": ("Dinner guests are parking outside",
                    "The restaurant kitchen is being cleaned before closing", "The café counter needs clearing",
                    "A baking class is about to start", "The holiday cottage must be spotless for check-in",
                    "The washing-up has been dried and stacked", "A food photographer is styling a shoot",
                    "The canteen opens for breakfast at seven", "A wedding buffet is being laid out",
                    "The caterers are packing their van"),
    "furniture": ("The bedroom is being tidied before the decorators come", "Moving day: every item is being checked",
                  "The hallway should look neat for the estate agent", "Spring cleaning has begun",
                  "The hotel room is being made up",
                  "An antiques dealer is valuing the furniture", "The removal van is booked for Monday",
                  "The guest room is being aired for visitors", "A carpenter is checking every hinge and runner",
                  "The landlady is doing the yearly inventory"),
    "appliance": ("Lunch needs heating up before the meeting", "The landlord is inspecting every appliance",
                  "A power cut just ended", "The office kitchen is shared by thirty people",
                  "The electrician is testing the sockets", "A student is cooking for the first time",
                  "The home help comes round on Tuesdays", "The show kitchen is open to viewers today"),
    "cold": ("The weekly shop has just been delivered", "A heatwave is forecast for the weekend",
             "The picnic drinks need chilling", "Leftover soup has cooled down enough",
             "The milk delivery has just arrived", "The freezer compartment is being defrosted"),
    "fixture": ("The houseplants by the window are wilting",
                "Someone has just come in from the muddy garden", "The kettle is empty and tea is overdue",
                "The plumber wants to check the water pressure", "The paint brushes need rinsing",
                "A hot summer day has left everyone thirsty", "The dog's water needs topping up"),
    "box": ("The craft supplies are being put away", "Parcels are being sorted in the mailroom",
            "The attic is being reorganised after the flood", "The study is being dusted for the week",
            "A photographer is packing up after a shoot", "The office is closing for the holidays"),
    "household": ("The power has gone out for the evening", "The lodger is moving into the spare room",
                  "The sitting room is being dusted before the visitors", "The shelves are being sorted for a move",
                  "A storm is forecast for tonight", "The cleaner comes on Thursday mornings",
                  "The hotel reception is opening for the day", "The flat is being readied for new tenants"),
    "desk": ("The office is being tidied before the audit", "The homework has just been finished",
             "The school secretary is sorting the post", "A new intern starts on Monday",
             "The reading room is closing for lunch", "The exam papers are being collated",
             "The shared desk is being cleared for the next shift"),
    "bathroom": ("The bathroom is being cleaned before the guests", "A hotel room is being made up for check-in",
                 "The children are getting ready for bed", "The gym changing room is being tidied",
                 "The washbasin shelf is cluttered", "Travel bags are being packed for the weekend",
                 "The spa opens in half an hour"),
    "waste": ("The floor is littered with scraps", "Rubbish collection is tomorrow morning",
              "The recycling rota says it is your turn", "The office party has just wound down",
              "A picnic has left wrappers everywhere", "The workshop bench is covered in offcuts"),
}
"""Situations a command may follow (``"<situation>: <command>."``), by what the main object is; ``{s}`` a word
for the table. No situation names a catalog object, nor presumes the task opens or closes something (those are in
:data:`SITUATIONS_DIRECTED`)."""

SITUATIONS_DIRECTED: dict[tuple[str, str], tuple[str, ...]] = {
    ("appliance", "open"): ("The leftovers from the party are waiting", "Breakfast porridge is ready to come out",
                            "A cake has to be checked for doneness"),
    ("appliance", "close"): ("The kitchen is being shut down for the night", "The timer has just been set"),
    ("cold", "open"): ("Breakfast needs something from the top shelf", "Someone wants a cold drink"),
    ("cold", "close"): ("The door alarm keeps beeping", "The ice cream is starting to melt"),
    ("furniture", "open"): ("Someone is hunting for a spare key", "The winter coats have to come out",
                            "A birthday present is hidden somewhere"),
    ("furniture", "close"): ("The toddler keeps bumping into everything", "The cat likes to climb inside anything",
                             "The room has to look finished for the photographs"),
    ("box", "open"): ("The remote control needs new batteries", "A treasure hunt clue is hidden somewhere",
                      "The party hats are packed away somewhere", "Someone needs the spare charger"),
    ("box", "close"): ("The dust sheets are going on before the painting", "The sand from the beach gets everywhere",
                       "The desk is being cleared for the night"),
    ("waste", "open"): ("Peelings from the stew need throwing away", "The vegetables have just been trimmed",
                        "The post came with a pile of junk mail"),
    ("waste", "close"): ("The flies are getting in", "The fox raided the garden last night",
                         "Guests are arriving and the kitchen should smell fresh"),
}
"""Situations that only suit a task that opens (or turns on) or one that closes something."""

PURPOSES: dict[str, tuple[str, ...]] = {
    "fruit": ("so it can be washed", "before it bruises", "for a healthy snack", "to go with the yoghurt",
              "ready for the juicer", "so the wasps leave it alone", "for the children's afternoon break",
              "so it can be peeled later", "to count the day's portions"),
    "food": ("so the recipe can start", "to check its best-before date", "ready for the picnic",
             "for the pantry inventory", "before the ants find it", "so the label can be read",
             "ready for the hungry hikers", "for the weekly meal plan"),
    "ball": ("so nobody trips over it", "ready for the next match", "to show the coach", "before the dog steals it",
             "before it rolls under the sofa", "so it is not lost again", "for the team photograph"),
    "toy": ("so the child can see it", "before the toddler wakes up", "for the toy photo shoot",
            "to finish the lesson", "so nobody steps on it", "before the parents come to collect"),
    "tool": ("so the job can continue", "to hand it to the mechanic", "before it gets lost",
             "so the bench can be swept", "before anyone cuts themselves", "so it can be oiled"),
    "kitchenware": ("so the table can be wiped", "before the guests sit down", "ready for dinner service",
                    "to make space for the cake", "so the crumbs can be brushed off", "before the inspector arrives"),
    "furniture": ("before the inspection", "before the viewing starts"),
    "appliance": ("so the kitchen can be cleaned", "before the landlord arrives"),
    "cold": ("before the shopping is unpacked",),
    "fixture": ("to fill the kettle", "to rinse the vegetables", "to water the basil", "to wash the mud off",
                "so the sink can be scrubbed"),
    "box": ("before the visitors come",),
    "waste": ("before the rubbish is collected",),
    "household": ("so the room looks tidy", "before anyone knocks it over", "so it is easy to find later",
                  "before the visitors arrive"),
    "desk": ("so the work can go on", "before the meeting starts", "so the desk is clear",
             "to hand it to a colleague"),
    "bathroom": ("so the shelf can be wiped", "before the guests use the bathroom", "ready for the morning",
                 "so it does not fall in the basin"),
}
"""Reasons a command may end with (``"<command>, <purpose>."``), by what the main object is of the part done
last; those that fit only an opening or a closing are in :data:`PURPOSES_DIRECTED`."""

PURPOSES_DIRECTED: dict[tuple[str, str], tuple[str, ...]] = {
    ("appliance", "open"): ("to check on the food", "to let the steam out", "to take out the warm leftovers"),
    ("appliance", "close"): ("to save energy", "to keep the heat in"),
    ("cold", "open"): ("to take out the milk", "to see what needs using up"),
    ("cold", "close"): ("to keep the food cold", "before anything spoils", "to save energy"),
    ("furniture", "open"): ("to air out the room", "to get at what is stored inside", "to find the spare towels"),
    ("furniture", "close"): ("so the hallway looks tidy", "so nobody walks into it", "to keep the dust out"),
    ("box", "open"): ("to find the batteries", "to check what is inside", "to take out the receipts"),
    ("box", "close"): ("so the dust stays out", "to keep the contents dry", "before it gets knocked over"),
    ("waste", "open"): ("so the scraps can go in", "to throw away the wrappers"),
    ("waste", "close"): ("to keep the smell in", "before the cat gets curious", "to keep the flies off"),
}
"""Reasons that only suit a task that opens (or turns on) or one that closes something."""

LEGACY_SITUATIONS = ("The sink is full of dirty dishes", "The dishwasher has just finished its cycle",
                     "A burglar alarm test needs every cupboard checked", "The toolbox is being sorted into trays",
                     "The butter is needed for the toast")
"""Situations earlier versions of the author used and no longer do (they name catalog objects); kept so
:func:`split` still takes them off instructions already written."""

SHAPES = (0.4, 0.7, 0.9)
"""Cumulative shares of the sentence shapes: situation + command, command + purpose, all three, the bare command."""

DOMAIN_OF_CATEGORY = {"refrigerator": "cold", "trash_can": "waste", "box_with_lid": "box", "faucet": "fixture",
                      "valve": "fixture", "laptop": "box", "knob": "appliance"}
DOMAIN_OF_TAG = (("fruit", "fruit"), ("food", "food"), ("ball", "ball"), ("toy", "toy"), ("toiletry", "bathroom"),
                 ("office", "desk"), ("household", "household"), ("tool", "tool"),
                 ("utensil", "kitchenware"), ("kitchenware", "kitchenware"), ("tableware", "kitchenware"),
                 ("appliance", "appliance"), ("furniture", "furniture"), ("fixture", "fixture"), ("box", "box"))


def domain(asset: dict) -> str:
    """What kind of thing ``asset`` is for the situation and purpose pools."""
    if asset["category"] in DOMAIN_OF_CATEGORY:
        return DOMAIN_OF_CATEGORY[asset["category"]]
    tags = set(asset.get("tags") or ())
    return next((d for t, d in DOMAIN_OF_TAG if t in tags), "kitchenware")


def names_for(asset: dict, qualifier: str = "") -> tuple[str, ...]:
    """Words for ``asset``: its category's synonyms, each with ``qualifier`` (e.g. ``"large"``) in front."""
    words = NAMES.get(asset["category"], (asset["category"].replace("_", " "),))
    return tuple(f"{qualifier} {w}" if qualifier else w for w in words)


def object_words(asset: dict) -> tuple[str, ...]:
    """Every word a command may call ``asset`` by: its synonyms with its model word (*compact microwave*) and
    without it."""
    return tuple(dict.fromkeys(names_for(asset, MODEL_WORDS.get(asset["id"], "")) + names_for(asset)))


def _pick(rng: np.random.Generator, options: Sequence[str]) -> str:
    return options[int(rng.integers(len(options)))]


def _sentence(text: str) -> str:
    text = text.strip()
    return text[:1].upper() + text[1:] + ("" if text.endswith((".", "!", "?")) else ".")


@dataclass(frozen=True)
class Part:
    """One thing a task asks for: a skill (a key of :data:`COMMANDS`) on catalog asset ``main``, with ``other`` the
    destination (container, plate, base block) where there is one; a qualifier tells two objects of the same
    category apart (*the small block on the large block*)."""

    skill: str
    main: dict
    other: dict | None = None
    main_qualifier: str = ""
    other_qualifier: str = ""
    amount: str = ""
    """How far a part-way open or turn goes, in words (*halfway*, *45 degrees*)."""
    pieces: str = ""
    """The catalog id of the pieces a pour pours (*beads*, *marbles*: :data:`PIECE_NAMES`)."""


def command(part: Part, rng: np.random.Generator, surface: str) -> str:
    """The bare command for ``part`` (no capital, no full stop)."""
    if part.skill not in COMMANDS:
        raise KeyError(f"no wording for skill {part.skill!r}; known: {sorted(COMMANDS)}")
    articulated = bool(part.main.get("joints"))
    o = _pick(rng, names_for(part.main, part.main_qualifier or MODEL_WORDS.get(part.main["id"], "")))
    d = _pick(rng, names_for(part.other, part.other_qualifier)) if part.other is not None else o
    p = _pick(rng, PIECE_NAMES.get(part.pieces, (part.pieces.replace("_", " ") + "s",))) if part.pieces else ""
    slots = dict(o=o, d=d if not articulated else o, s=surface, a=part.amount, p=p)
    template = _pick(rng, COMMANDS[part.skill])
    if awkward(template, slots):  # another of the skill's templates (drawn as before where the first one reads well)
        template = _pick(rng, [t for t in COMMANDS[part.skill] if not awkward(t, slots)] or [template])
    return template.format(**slots)


def awkward(template: str, slots: dict[str, str]) -> bool:
    """Whether ``template`` filled with ``slots`` makes a possessive of a name with *of* or *with* in it (*the
    chest of drawers's drawer*, *the box with a lid's lid*)."""
    return any(re.search(r" (of|with) ", v) and f"{{{k}}}'s" in template for k, v in slots.items())


def qualifiers(a: dict, b: dict | None, colors: tuple[str | None, ...] = ()) -> dict[str, str]:
    """Words that tell objects apart in a sentence: the colours the task paints them (``colors``: the main object's,
    then the other's), then, for two of one category, their sizes from their ids (*the red medium block on the blue
    large block*)."""
    same = b is not None and a["category"] == b["category"]
    out = {}
    for key, x, color in (("main_qualifier", a, colors[0] if colors else None),
                          ("other_qualifier", b, colors[1] if len(colors) > 1 else None)):
        if x is not None:
            words = [w for w in (color, x["id"].split("_")[-1] if same else None) if w]
            if words:
                out[key] = " ".join(words)
    return out


def painted(a: dict, colors: tuple[str | None, ...], k: int) -> tuple[str, ...]:
    """The words of a task name for ``a`` painted ``colors[k]`` (if any): ``("red", "block_small")``."""
    return (colors[k], a["id"]) if len(colors) > k and colors[k] else (a["id"],)


def phrase(skill: str, main: dict, rng: np.random.Generator, *, other: dict | None = None,
           main_qualifier: str = "", other_qualifier: str = "", amount: str = "", pieces: str = "",
           choose: Chooser | None = None) -> str:
    """An instruction for one :class:`Part` (see there and :func:`phrase_parts` for the arguments)."""
    return phrase_parts([Part(skill, main, other, main_qualifier, other_qualifier, amount, pieces)], rng,
                        choose=choose)


def direction(skill: str) -> str | None:
    """``"open"`` for a skill that opens or turns something on, ``"close"`` for one that closes, else None. A press
    switches on and a twist unscrews: both open."""
    if skill.startswith(("open_", "press_")) or skill in ("turn", "turn_part", "press", "twist"):
        return "open"
    if skill.startswith("close_") or skill in ("turn_off", "twist_on"):
        return "close"
    return None


@dataclass(frozen=True)
class Frame:
    """What the situation or purpose of a sentence is about: the domain of a part's main object and whether that
    part opens or closes something (None: neither)."""

    domain: str
    direction: str | None = None

    @classmethod
    def of(cls, part: Part) -> Frame:
        return cls(domain(part.main), direction(part.skill))


def situations(frame: Frame) -> tuple[str, ...]:
    """The situations that suit ``frame`` (``{s}`` still to fill in)."""
    return SITUATIONS[frame.domain] + SITUATIONS_DIRECTED.get((frame.domain, frame.direction or ""), ())


def purposes(frame: Frame) -> tuple[str, ...]:
    """The purposes that suit ``frame``."""
    return PURPOSES[frame.domain] + PURPOSES_DIRECTED.get((frame.domain, frame.direction or ""), ())


def framings(text: str, first: Frame, last: Frame, surface: str) -> list[str]:
    """Every sentence the author may make of the bare command ``text``: alone, after a situation about ``first``,
    before a purpose about ``last``, or both (the bare command first)."""
    sits = [x.format(s=surface) for x in situations(first)]
    purps = purposes(last)
    out = [_sentence(text)]
    out += [_sentence(f"{x}: {text}") for x in sits]
    out += [_sentence(f"{text}, {p}") for p in purps]
    out += [_sentence(f"{x}: {text}, {p}") for x in sits for p in purps]
    return out


def phrase_parts(parts: list[Part], rng: np.random.Generator, choose: Chooser | None = None) -> str:
    """An instruction for a task of one or more parts done in turn (*..., then ...*), with a situation from the
    first part's main object and a purpose from the last one's (or neither, or one of them).

    Without ``choose`` the sentence's shape, situation and purpose are drawn from ``rng``; with it, ``choose`` picks
    from every framing of the drawn command (:func:`framings`), e.g. the one least like the library's
    instructions (:class:`generator.reword.LibraryWording`)."""
    surface = _pick(rng, SURFACES)
    text = ", then ".join(command(p, rng, surface) for p in parts)
    first, last = Frame.of(parts[0]), Frame.of(parts[-1])
    if choose is not None:
        return choose(framings(text, first, last, surface))
    shape = rng.random()
    situation = _pick(rng, situations(first)).format(s=surface)
    purpose = _pick(rng, purposes(last))
    if shape < SHAPES[0]:
        return _sentence(f"{situation}: {text}")
    if shape < SHAPES[1]:
        return _sentence(f"{text}, {purpose}")
    if shape < SHAPES[2]:
        return _sentence(f"{situation}: {text}, {purpose}")
    return _sentence(text)


@functools.cache
def _all_situations() -> tuple[str, ...]:
    """Every situation the author writes or wrote, filled in with every surface word, longest first."""
    found = set(LEGACY_SITUATIONS)
    for pool in (*SITUATIONS.values(), *SITUATIONS_DIRECTED.values()):
        for x in pool:
            found |= {x.format(s=s) for s in SURFACES}
    return tuple(sorted(found, key=len, reverse=True))


@functools.cache
def _all_purposes() -> tuple[str, ...]:
    found = {p for pool in (*PURPOSES.values(), *PURPOSES_DIRECTED.values()) for p in pool}
    return tuple(sorted(found, key=len, reverse=True))


def split(instruction: str) -> tuple[str | None, str, str | None]:
    """``(situation, command, purpose)`` of an instruction this author wrote (the command without capital or full
    stop; None for a part it does not have). A sentence the author did not write is all command."""
    text = instruction.strip().rstrip(".")
    situation = next((x for x in _all_situations() if text.startswith(x + ": ")), None)
    if situation is not None:
        text = text[len(situation) + 2:]
    purpose = next((p for p in _all_purposes() if text.endswith(", " + p)), None)
    if purpose is not None:
        text = text[: -len(purpose) - 2]
    return situation, text[:1].lower() + text[1:] if situation is None else text, purpose


__all__ = ["COMMANDS", "MODEL_WORDS", "NAMES", "PIECE_NAMES", "PLACE_AT", "PURPOSES", "PURPOSES_DIRECTED", "SITUATIONS",
           "SITUATIONS_DIRECTED", "Chooser", "Frame", "Part", "awkward", "command", "direction", "domain", "framings",
           "names_for", "object_words", "phrase", "painted", "phrase_parts", "purposes", "qualifiers", "situations",
           "split"]

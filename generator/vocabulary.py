"""The words of requests: the task skills with their verbs (:data:`TASK_SKILLS`), what people call catalog objects
(:data:`SYNONYMS`), kinds of object (:data:`KINDS`) and the parts of articulated objects (:data:`PARTS`).
:mod:`generator.instruction` reads requests with them; the language-model prompts list them."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TaskSkill:
    """One thing a person can ask for."""

    name: str
    verbs: tuple[str, ...]
    """Verb phrases that ask for it (lower case, matched on word boundaries)."""
    objects: str
    """What it acts on, in words (for messages and prompts)."""
    example: str


TASK_SKILLS: dict[str, TaskSkill] = {s.name: s for s in (
    TaskSkill("lift", ("pick up", "pick", "grab", "grasp", "lift", "raise", "hold up", "hold", "take", "get",
                       "hoist"),
              "a graspable object", "pick up the apple"),
    TaskSkill("put_in", ("put", "place", "drop", "insert", "move", "transfer", "deposit", "pop", "stow", "tuck",
                         "store"),
              "a graspable object and a container (bowl, pot, mug, a box or bin with a lid, a drawer), with 'in' or "
              "'into'",
              "put the lemon in the bowl"),
    TaskSkill("place_on", ("set", "put", "place", "lay", "move", "rest"),
              "a graspable object and a plate, tray or cutting board, with 'on' or 'onto'",
              "set the bottle on the plate"),
    TaskSkill("stack", ("stack", "pile", "balance"), "two blocks", "stack the small block on the large block"),
    TaskSkill("push", ("push", "slide", "shove", "nudge"), "an object on the table, pushed to a goal mark",
              "push the block to the goal"),
    TaskSkill("open", ("open", "pull open", "lift open", "unlatch", "raise the lid", "pull", "flip up", "flip open"),
              "a door, drawer or lid (cabinet, microwave, refrigerator, drawer chest, trash can, box with lid)",
              "open the top drawer"),
    TaskSkill("close", ("close", "shut", "push shut", "push closed"),
              "a door, drawer or lid (cabinet, microwave, drawer chest, trash can)", "close the cabinet door"),
    TaskSkill("turn", ("turn on", "switch on", "turn", "twist", "swing", "turn off", "switch off", "switch"),
              "a faucet or valve lever, on or off", "turn on the faucet"),
    TaskSkill("press", ("press", "push down", "hit", "click", "depress", "flip", "toggle", "punch", "smash"),
              "a button pressed all the way down, or a lever switch flipped on", "press the emergency stop button"),
    TaskSkill("reorient", ("rotate", "spin", "reorient", "roll"),
              "a ball held in the hand (a trained in-hand policy)", "rotate the tennis ball in the hand"),
    TaskSkill("take_out", ("take out", "get out", "lift out", "pull out", "fish out", "remove"),
              "a graspable object taken out of a container (bowl, pot) or a drawer and set down on the table beside it",
              "take the apple out of the bowl"),
    TaskSkill("place_at", (), "a graspable object set down left or right of, in front of, behind, next to or between "
              "other objects, or in a region of the table (far left, near side, middle), as the robot sees it",
              "put the apple to the left of the bowl"),
    TaskSkill("twist", ("unscrew", "twist off", "twist open", "screw off", "untwist", "loosen", "screw", "tighten"),
              "a jar lid or bottle cap unscrewed a full turn, regrasped between turns of the hand (jar, wide-mouth "
              "bottle, canister)", "unscrew the jar lid"),
    TaskSkill("insert", ("insert", "plug", "slot", "fit", "peg"),
              "a peg put into the hole of its holder (2.5-3 mm of clearance a side), upright, and let go: a round, "
              "square or thin peg", "insert the square peg into the square hole"),
    TaskSkill("wipe", ("wipe up", "wipe", "clean up", "clean", "scrub", "mop up", "mop", "sponge"),
              "a spill on the table wiped with a sponge pressed down on it, over at least 90 % of its marks (a round, "
              "square or long spill)", "wipe the spill with the sponge"),
    TaskSkill("hang", ("hang up", "hang"),
              "a mug hung by its handle on a peg of a mug hook, mug tree or mug rack, and let go (it hangs there, "
              "off the table, at rest)", "hang the mug on the mug tree"),
    TaskSkill("pour", ("pour out", "pour", "tip out", "tip", "empty out", "empty"),
              "the beads or marbles in a glass, beaker or paper cup poured into a bowl (at least 75 % of them), and "
              "the vessel stood up again", "pour the beads from the glass into the bowl"),
    TaskSkill("flip", ("turn upside down", "turn over", "flip over", "flip", "upend", "invert", "overturn"),
              "a glass, beaker or paper cup turned upside down on the table (standing on its rim), let go and still",
              "turn the glass upside down"),
    TaskSkill("hand_over", ("hand over", "hand me", "hand it", "hand off", "pass me", "pass over", "pass it", "pass",
                            "give me", "bring me", "deliver"),
              "a graspable object left on the hand-over mat for a person to take: let go, still, upright if it stood",
              "hand me the bottle"),
)}
"""The task skills a request may ask for, in the order verbs are tried (earlier skills win ties)."""

SYNONYMS: dict[str, str] = {
    # phrase -> catalog category (or id)
    "box of sugar": "sugar_box", "box of pudding": "pudding_box", "box of crackers": "cracker_box",
    "box of gelatin": "gelatin_box", "jelly box": "gelatin_box", "kitchen sponge": "sponge", "dish sponge": "sponge",
    "stove oven": "oven", "dish washer": "dishwasher",
    "fridge": "refrigerator", "refrigerator": "refrigerator", "cupboard": "cabinet", "cabinet": "cabinet",
    "closet": "cabinet", "trash can": "trash_can", "trashcan": "trash_can", "trash bin": "trash_can",
    "bin": "trash_can", "garbage can": "trash_can", "dustbin": "trash_can", "waste bin": "trash_can",
    "tap": "faucet", "faucet": "faucet", "mixer tap": "faucet", "drawer": "drawer_chest", "drawers": "drawer_chest",
    "dresser": "drawer_chest", "chest of drawers": "drawer_chest", "chest": "drawer_chest",
    "microwave oven": "microwave",
    "coffee mug": "mug", "cup": "cup", "glass": "wine_glass", "wineglass": "wine_glass", "jug": "pitcher",
    "saucepan": "pot", "pan": "pot", "cooking pot": "pot", "dish": "plate", "saucer": "plate", "cube": "block",
    "brick": "foam_brick", "die": "dice", "notebook": "laptop", "computer": "laptop", "lidded box": "box_with_lid",
    "box with a lid": "box_with_lid", "rubik's cube": "rubiks_cube", "rubik cube": "rubiks_cube",
    "bottle of mustard": "mustard_bottle", "soup can": "can", "tin": "can", "tin can": "can", "duck": "toy_duck",
    "rubber duck": "toy_duck", "pen": "marker", "felt pen": "marker", "dial": "knob",
    "tin of tuna": "tuna_can", "serving bowl": "bowl", "mixing bowl": "bowl", "dinner plate": "plate",
    "teacup": "cup", "soft brick": "foam_brick", "puzzle cube": "rubiks_cube", "drawer unit": "drawer_chest",
    "storage box": "box_with_lid", "notebook computer": "laptop", "stove knob": "knob_stove",
    "chopping board": "cutting_board", "serving tray": "tray", "ball valve": "valve", "shutoff valve": "valve",
    "stopcock": "valve", "emergency stop": "button_estop", "emergency stop button": "button_estop",
    "estop": "button_estop", "stop button": "button_estop", "kill switch": "button_estop",
    "arcade button": "button_arcade", "push button": "button", "pushbutton": "button", "buzzer": "button_arcade",
    "game button": "button_arcade", "light switch": "switch", "toggle switch": "switch", "lever switch": "switch",
    "breaker": "switch", "power switch": "switch", "tall switch": "switch_lever_tall",
    "peg holder": "peg_holder", "holder": "peg_holder", "peg hole": "peg_holder", "peg board": "peg_holder",
    "pegboard": "peg_holder", "hole": "peg_holder", "round hole": "peg_holder_round",
    "square hole": "peg_holder_square",
    "thin hole": "peg_holder_thin", "small hole": "peg_holder_thin", "narrow hole": "peg_holder_thin",
    "stain": "spill", "mess": "spill", "puddle": "spill", "round spill": "spill_round",
    "round stain": "spill_round", "puddle of coffee": "spill_round", "coffee spill": "spill_round",
    "square spill": "spill_square", "square stain": "spill_square", "juice spill": "spill_square",
    "long spill": "spill_long", "long stain": "spill_long", "streak": "spill_long", "sauce spill": "spill_long",
    "car sponge": "sponge_block", "foam sponge": "sponge_block", "thick sponge": "sponge_block",
    "sponge block": "sponge_block", "big sponge": "sponge_block",
    "hook": "mug_hook", "wall hook": "mug_hook", "cup hook": "mug_hook", "coat hook": "mug_hook",
    "mug stand": "mug_tree", "cup tree": "mug_tree", "tree": "mug_tree", "wall rack": "mug_rack",
    "cup rack": "mug_rack", "hanging rack": "mug_rack", "rack": "mug_rack",
    "drinking glass": "tumbler", "water glass": "tumbler", "tumbler glass": "tumbler", "lab beaker": "beaker",
    "measuring beaker": "beaker", "glass beaker": "beaker", "disposable cup": "paper_cup",
    "takeaway cup": "paper_cup", "coffee cup": "paper_cup", "marbles": "marble", "glass marbles": "marble",
    "glass beads": "marble", "pellets": "bead", "ceramic beads": "bead",
    "round peg": "peg_round", "square peg": "peg_square", "thin peg": "peg_thin", "dowel": "peg_thin",
    "hand over mat": "handover_mat", "hand over zone": "handover_mat", "handover zone": "handover_mat",
    "hand over area": "handover_mat", "handover area": "handover_mat", "hand over spot": "handover_mat",
    "handover spot": "handover_mat", "mat": "handover_mat", "yellow mat": "handover_mat",
    "jam jar": "jar", "glass jar": "jar", "mason jar": "jar", "kitchen canister": "canister",
    "tin canister": "canister",
    "wide mouth bottle": "screw_bottle", "water bottle": "screw_bottle", "sports bottle": "screw_bottle",
    # everyday objects (gendex_envs.assets.procedural_household)
    "kiwifruit": "kiwi", "kiwi fruit": "kiwi", "capsicum": "bell_pepper", "sweet pepper": "bell_pepper",
    "pepper": "bell_pepper", "spud": "potato", "garlic bulb": "garlic",
    "head of garlic": "garlic", "hen's egg": "egg", "salt": "salt_shaker", "salt cellar": "salt_shaker",
    "shaker": "salt_shaker", "pepper grinder": "pepper_mill", "grinder": "pepper_mill", "spice": "spice_jar",
    "yoghurt cup": "yogurt_cup", "yogurt pot": "yogurt_cup", "pot of yogurt": "yogurt_cup",
    "carton of milk": "milk_carton", "juice carton": "juice_box", "juice": "juice_box",
    "drink box": "juice_box", "wax candle": "candle", "pillar candle": "candle", "shampoo": "shampoo_bottle",
    "bottle of shampoo": "shampoo_bottle", "toothpaste": "toothpaste_tube", "tube of toothpaste": "toothpaste_tube",
    "soap": "soap_bar", "bar of soap": "soap_bar", "desk bell": "service_bell", "bell": "service_bell",
    "torch": "flashlight", "tape": "tape_roll", "roll of tape": "tape_roll", "duct tape": "tape_roll",
    "roll of duct tape": "tape_roll",
    "sticky tape": "tape_roll", "billiard ball": "pool_ball", "snooker ball": "pool_ball",
    "bouncy ball": "rubber_ball", "king": "chess_king", "rook": "chess_rook", "castle": "chess_rook",
    "car": "toy_car", "model car": "toy_car", "teddy": "teddy_bear",
    "bear": "teddy_bear", "stuffed bear": "teddy_bear", "wicker basket": "basket", "fruit basket": "basket",
    "casserole dish": "baking_dish", "oven dish": "baking_dish", "roasting dish": "baking_dish",
    "crate": "storage_bin", "tub": "storage_bin", "plastic bin": "storage_bin", "place mat": "placemat",
    "table mat": "placemat", "baking tray": "baking_sheet", "sheet pan": "baking_sheet",
    "cookie sheet": "baking_sheet", "oven tray": "baking_sheet",
    # the pantry and the home (procedural_pantry, procedural_home), and the colour variants' own kinds
    "can of soda": "soda_can", "drinks can": "soda_can", "soft drink can": "soda_can", "cola can": "soda_can",
    "pepper pot": "pepper_shaker", "courgette": "zucchini", "aubergine": "eggplant", "yam": "sweet_potato",
    "ear of corn": "corn", "corn cob": "corn", "mini pumpkin": "pumpkin", "beet": "beetroot",
    "ketchup": "ketchup_bottle", "bottle of ketchup": "ketchup_bottle", "honey": "honey_jar",
    "jar of honey": "honey_jar", "olive oil": "olive_oil_bottle", "bottle of olive oil": "olive_oil_bottle",
    "oil bottle": "olive_oil_bottle", "beer": "beer_bottle", "bottle of beer": "beer_bottle",
    "tub of ice cream": "ice_cream_tub", "tin of tea": "tea_tin",
    "tea caddy": "tea_tin", "block of butter": "butter", "box of cereal": "cereal_box", "wedge of cheese": "cheese",
    "cheese wedge": "cheese", "bun": "bread_roll", "doughnut": "donut", "pawn": "chess_pawn",
    "bishop": "chess_bishop", "queen": "chess_queen", "knight": "chess_knight", "skittle": "bowling_pin",
    "alphabet block": "letter_block", "train": "toy_train", "boat": "toy_boat", "money box": "piggy_bank",
    "bottle of lotion": "lotion_bottle", "pump bottle": "lotion_bottle", "deodorant stick": "deodorant",
    "box of tissues": "tissue_box", "bottle of perfume": "perfume_bottle", "perfume": "perfume_bottle",
    "bath sponge": "loofah", "toilet paper": "toilet_roll", "roll of toilet paper": "toilet_roll",
    "glue": "glue_bottle", "bottle of glue": "glue_bottle", "board eraser": "whiteboard_eraser",
    "eraser": "whiteboard_eraser", "paper punch": "hole_punch", "bulb": "light_bulb", "lightbulb": "light_bulb",
    "sand timer": "hourglass", "tin of paint": "paint_can", "paint tin": "paint_can", "clock": "alarm_clock",
    "plant pot": "flower_pot",
}
"""Words people use for catalog objects: phrase -> catalog category or id."""

POUR_VESSELS: dict[str, str] = {"glass": "tumbler", "cup": "paper_cup", "beaker": "beaker", "tumbler": "tumbler"}
"""What a vessel named in a pour is, where the word names no vessel one pours from (a glass of beads is a tumbler,
not a wine glass; a cup of them a paper cup, not a teacup)."""

KINDS: dict[str, str] = {"fruit": "fruit", "ball": "ball", "toy": "toy", "block": "block", "food": "food",
                         "vegetable": "vegetable", "veggie": "vegetable", "toiletry": "toiletry",
                         "tool": "tool", "utensil": "utensil", "container": "container", "box": "box",
                         "thing": "graspable", "object": "graspable", "item": "graspable"}
"""Words naming a kind of object (a catalog tag): 'a fruit' is any fruit; which one is a recorded choice."""

PARTS = ("door", "drawer", "lid", "lever", "handle", "knob", "rack", "tab", "cap")
"""Words naming the part of an articulated object a skill acts on (recorded, never an object on their own)."""
ORDINALS = {"top": "top", "upper": "top", "bottom": "bottom", "lower": "bottom", "first": "top", "second": "second"}

STOP_WORDS = frozenset(
    "a an the this that these those its it of to from with by and then please robot hand your my up "
    "down off out over at for some one along until toward towards near beside behind below above "
    "under between while without through so"
    .split())
FILLER_WORDS = frozenset(
    "into inside onto top hand goal mark table shut closed open side around across upright away back "
    "there here target spot marked place position edge middle centre center surface counter worktop "
    "tabletop air way width tower floor person someone somebody human people user operator colleague partner "
    "friend guest customer"
    .split())
"""Words after the verb that name no object (places on the table among them)."""
COURTESY_WORDS = frozenset(
    "please could can would will you kindly now just go ahead i we want need like let lets us me thanks thank"
    .split())
"""Words of how a request is asked that shape no task (*could you please ...*): read, and dropped."""


__all__ = ["COURTESY_WORDS", "FILLER_WORDS", "KINDS", "ORDINALS", "PARTS", "POUR_VESSELS", "STOP_WORDS", "SYNONYMS",
           "TASK_SKILLS", "TaskSkill"]

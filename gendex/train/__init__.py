"""PPO training of task stages (``gendex train``) and the paper's four-variant ablation (``gendex ablate``)."""

"""Table I's study: the evaluation behind ``cadsim evaluate`` (``evaluation.py``), dataset
spread (``spread.py``) and the regime cards (``regime_cards.py``)."""

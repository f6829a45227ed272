"""What the command line and the tools show a person: text and CSV tables (:mod:`.text`) and
figures drawn with matplotlib (:mod:`.plots`, the ``plot`` extra)."""

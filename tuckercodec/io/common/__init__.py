"""What several format readers and writers share, none of them a format itself: faces stored
flat (:mod:`.polygons`), the ceiling of what one read may inflate (:mod:`.budget`), XML parsed
without declarations (:mod:`.safe_xml`) and the shortest round-trip text of floats
(:mod:`.float_text`)."""

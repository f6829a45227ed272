"""The Tucker decomposition of a centred sequence (:mod:`.hosvd`) and the exact error of every
truncation (i, 3, k) it allows, with the seed paper's bound beside it (:mod:`.analysis`)."""

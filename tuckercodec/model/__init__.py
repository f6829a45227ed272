"""The in-memory model of an animated mesh, which every other layer speaks: the sequence
(:mod:`.sequence`), a sequence read a range of frames at a time (:mod:`.sources`), and the face
table and what follows from it (:mod:`.topology`). It knows no file format."""

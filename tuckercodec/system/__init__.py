"""The process and the machine, below everything else: writing files so that nothing is lost
(:mod:`.atomic`), opening inputs that cannot block (:mod:`.reading`), the optional libraries
(:mod:`.optional`), where tasks run (:mod:`.parallel`), and a progress bar (:mod:`.progress`).
Nothing here knows about meshes or the file format."""

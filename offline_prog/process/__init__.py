"""What the part gets along the path (the paper's outlook: process quality from a model
of the process): the bead's cross-section, the weld's heat input, the tape's nip
temperature, each predicted from the planned speed and the outputs as the programs set
them. ``model.process_model(cell)`` is the one factory."""

"""move_base and its parts: costmaps, planners, recoveries."""

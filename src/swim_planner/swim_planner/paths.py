"""Where swim_planner keeps its shipped data."""
from importlib import resources
from pathlib import Path


def default_library_path() -> Path:
    """The primitive library shipped with swim_planner (built by `swim-primitives build`)."""
    return Path(str(resources.files("swim_planner") / "library" / "default"))

"""Where swim_planner keeps its shipped data."""
from importlib import resources
from pathlib import Path

from swim_planner.errors import LibraryError

#: the shipped libraries' folders by flow model: the paper's ideal flow, and swim_model.flow's circulatory one
SHIPPED_LIBRARY_FOLDERS = {"ideal": "default", "circulatory": "circulatory"}


def default_library_path(flow_model: str = "ideal") -> Path:
    """The primitive library shipped with swim_planner for a flow model (built by `swim-primitives build`)."""
    try:
        folder = SHIPPED_LIBRARY_FOLDERS[flow_model]
    except KeyError:
        raise LibraryError(f"no shipped library for flow model {flow_model!r}: one of "
                         f"{', '.join(SHIPPED_LIBRARY_FOLDERS)}") from None
    return Path(str(resources.files("swim_planner") / "library" / folder))

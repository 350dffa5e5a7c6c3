"""pteryla.Error: bad input, naming the file and the element where it is (pteryla::Error)."""


class Error(Exception):
    """Bad input: an array, a set-up field, a scene or feather file.

    Attributes: ``file`` (the input file, "" for in-memory input), ``element`` (where: "positions",
    "vertex 17", "face 3", "tracts[0].density", ...) and ``detail`` (what was wrong, without the place).
    """

    def __init__(self, message, file="", element="", detail=None):
        super().__init__(message)
        self.file = file
        self.element = element
        self.detail = message if detail is None else detail

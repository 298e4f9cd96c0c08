# hmc.pyi names what the module has, no more and no less, so editors complete and check calls.
import ast
import inspect
import os

import hmc

STUBS = os.path.join(os.path.dirname(hmc.__file__), "hmc.pyi")
ALIASES = {"Number", "QuantityLike", "AxisLike", "Colour", "PathLike"}


def stub_tree():
    with open(STUBS) as f:
        return ast.parse(f.read())


def test_stubs_sit_beside_the_module():
    assert os.path.exists(STUBS)


def test_every_public_name_is_in_the_stubs_and_back():
    tree = stub_tree()
    stubbed = {n.name for n in tree.body if isinstance(n, (ast.ClassDef, ast.FunctionDef))}
    public = {name for name in dir(hmc) if not name.startswith("_")}
    assert stubbed == public


def test_board_methods_and_their_keywords():
    tree = stub_tree()
    board = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Board")
    stubbed = {n.name: n for n in board.body if isinstance(n, ast.FunctionDef)}
    public = {name for name in dir(hmc.Board) if not name.startswith("_")}
    assert set(stubbed) - {"__enter__", "__exit__"} == public
    for name in ("move", "run", "open"):
        target = stubbed.get(name) or next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == name)
        keywords = [a.arg for a in target.args.args + target.args.kwonlyargs if a.arg != "self"]
        doc = (getattr(hmc.Board, name, None) or getattr(hmc, name)).__doc__
        for keyword in keywords:
            assert f"{keyword}" in doc.split("\n")[0], (name, keyword)


def test_every_record_field_is_stubbed():
    tree = stub_tree()
    for node in tree.body:
        if not isinstance(node, ast.ClassDef) or node.name in ALIASES:
            continue
        fields = {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        cls = getattr(hmc, node.name)
        if fields and not issubclass(cls, BaseException):  # exceptions' attributes are the instance's
            actual = {name for name, _ in inspect.getmembers(cls) if not name.startswith("_")}
            assert fields == actual, (node.name, fields ^ actual)

"""Sphinx configuration of the API reference: ``make docs`` builds it into docs/_build/html."""

import ast
import importlib
import inspect
import os
import pkgutil
import re
import sys

# The checkout's package, not whichever dynia happens to be installed.
sys.path.insert(0, os.path.abspath(".."))

from sphinx.pycode import ModuleAnalyzer  # noqa: E402

import dynia  # noqa: E402

project = "dynia"
author = "dynia contributors"
release = version = dynia.__version__

extensions = ["sphinx.ext.autodoc", "numpydoc"]

html_theme = "alabaster"
exclude_patterns = ["_build"]

autodoc_default_options = {"members": True, "undoc-members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
# The numpydoc sections say the types; the few annotations would only repeat them.
autodoc_typehints = "none"

# autodoc already lists the members; numpydoc's extra summary tables would list them twice.
numpydoc_show_class_members = False

# nitpicky (-n) makes every unresolved cross-reference an error, so that a docstring pointing at a module
# or function that moved fails the build. Only names of other packages are let through: the build never
# downloads their inventories (no network), so they cannot resolve here.
nitpick_ignore_regex = [
    (r"py:.*", r"(numpy|np|xarray|xr|pandas|pd|matplotlib|scipy|control|dask|distributed|numba)(\..*)?"),
    (r"py:.*", r"(datetime|collections)(\..*)?"),
]

# Not documented: the deprecated shims and the two aliases of dynia.reference's modules.
UNDOCUMENTED = {"dynia.analysis", "dynia.cld", "dynia.thesis", "dynia.mcat", "dynia.cli.__main__"}
API = os.path.join(os.path.dirname(__file__), "api")


def public_modules():
    """Every module of the package a user may import: the private ones (``_name``) and UNDOCUMENTED left out."""
    names = ["dynia"]
    for info in pkgutil.walk_packages(dynia.__path__, "dynia."):
        if not any(part.startswith("_") for part in info.name.split(".")) and info.name not in UNDOCUMENTED:
            names.append(info.name)
    return names


def check_pages(app):
    """Fail the build when a public module has no page under docs/api, or a page names no module."""
    pages = {name[: -len(".rst")] for name in os.listdir(API) if name.endswith(".rst")}
    modules = set(public_modules())
    if pages != modules:
        raise RuntimeError(
            f"docs/api: pages missing for {sorted(modules - pages)}, pages without a module {sorted(pages - modules)}"
        )


def exported_names(package):
    """reST for the names a package exports from its modules, each pointing at where it is documented.

    The package pages leave their members out (each is documented once, in its own module), and dynia's
    verbs are loaded lazily, so autodoc would not find them anyway; listed here from ``__all__``, every
    exported name is a target (``dynia.run``, ``dynia.models.FOPDT``) and none can be forgotten.
    """
    module = importlib.import_module(package)
    lines = []
    for name in getattr(module, "__all__", ()):
        obj = getattr(module, name)
        if inspect.ismodule(obj) or f"{package}.{name}" in sys.modules:
            continue
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue  # constants: documented in the module that defines them (module_data)
        if obj.__module__ == package:
            # Defined in the package itself (dynia.cli.main): documented here, its one home.
            lines += [f".. auto{'class' if inspect.isclass(obj) else 'function'}:: {package}.{name}", ""]
            continue
        home = f"{obj.__module__}.{obj.__qualname__}"
        if inspect.isclass(obj):
            kind, role = ("exception", "exc") if issubclass(obj, BaseException) else ("class", "class")
        else:
            kind, role = "function", "func"
        lines += [f".. py:{kind}:: {name}", f"   :module: {package}", ""]
        lines += [f"   Documented as :{role}:`{home}`.", ""]
    return ["", "Exported names", "--------------", "", *lines] if lines else []


def module_data(modname):
    """reST for the module's public constants that autodoc leaves out: those without a ``#:`` comment.

    Docstrings refer to them (``:data:`MAX_SAMPLES```), so each needs a target. Each shows its value and the
    comment above it, escaped: a comment is not written as reST, and must not break the build.
    """
    module = importlib.import_module(modname)
    attr_docs = ModuleAnalyzer.for_module(modname).find_attr_docs()
    with_doc_comment = {name for namespace, name in attr_docs if not namespace}
    exported = getattr(module, "__all__", None)
    source = inspect.getsource(module)
    source_lines = source.splitlines()
    lines, seen = [], set()
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, ast.AnnAssign):
            targets = [node.target]
        else:
            continue
        comment = []
        for line in reversed(source_lines[: node.lineno - 1]):
            if not line.startswith("#"):
                break
            comment.insert(0, line.lstrip("#").strip())
        for target in targets:
            name = getattr(target, "id", "_")
            if name.startswith("_") or name in seen:
                continue
            seen.add(name)
            if name in with_doc_comment and (exported is None or name in exported):
                continue
            value = repr(getattr(module, name))
            lines.append(f".. py:data:: {name}")
            lines.append(f"   :module: {modname}")
            if len(value) <= 200 and "\n" not in value:
                lines.append(f"   :value: {value}")
            lines.append("")
            if comment:
                lines += ["   " + re.sub(r"([\\`*_|\[\]<>:])", r"\\\1", " ".join(comment)), ""]
    return ["", "Constants", "---------", "", *lines] if lines else []


def add_generated(app, docname, source):
    if docname.startswith("api/"):
        modname = docname[len("api/") :]
        # Package pages leave their members out (:no-members:); a module's page documents its __all__ itself.
        exported = exported_names(modname) if hasattr(importlib.import_module(modname), "__path__") else []
        source[0] += "\n".join([*exported, *module_data(modname)]) + "\n"


def public_bases(app, name, obj, options, bases):
    """Show a private base class (``_Lag``) as the public classes it derives from: it has no page to link to."""
    index = 0
    while index < len(bases):
        if bases[index].__name__.startswith("_"):
            bases[index : index + 1] = [base for base in bases[index].__bases__ if base not in bases]
        else:
            index += 1


def setup(app):
    app.connect("builder-inited", check_pages)
    app.connect("source-read", add_generated)
    app.connect("autodoc-process-bases", public_bases)

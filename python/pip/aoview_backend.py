"""pip's build backend for aoview (pyproject.toml): meson-python's hooks, which build the package with
meson, where meson-python is found; where it is not, hooks that say what to install (pip would
otherwise print a bare ModuleNotFoundError traceback)."""
HOOKS = ('build_wheel', 'build_sdist', 'get_requires_for_build_wheel', 'get_requires_for_build_sdist',
         'prepare_metadata_for_build_wheel', 'build_editable', 'get_requires_for_build_editable',
         'prepare_metadata_for_build_editable')

try:
    import mesonpy
except ModuleNotFoundError as missing:
    REASON = str(missing)

    def _missing(*args, **kwargs):
        raise SystemExit(f"aoview's pip build needs meson-python ({REASON}). On Debian: apt install "
                         'python3-mesonpy python3-numpy, make the virtual environment with --system-site-packages '
                         'and pip install --no-build-isolation . (docs/python.md); elsewhere: pip install '
                         'meson-python numpy, or let pip fetch them (without --no-build-isolation).')

    build_wheel = build_sdist = get_requires_for_build_wheel = get_requires_for_build_sdist = _missing
else:
    globals().update({hook: getattr(mesonpy, hook) for hook in HOOKS if hasattr(mesonpy, hook)})

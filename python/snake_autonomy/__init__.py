"""snake_autonomy: autonomy stack for modular snake robots (COBRA first)."""

# Found first on sys.path (a spawned process, e.g. a Dask worker, gets its parent's sys.path with
# the source folder ahead of the devel space): the compiled _core and generated msg modules live in
# the other snake_autonomy folders of sys.path.
__path__ = __import__("pkgutil").extend_path(__path__, __name__)

"""The package's version (summary.json's package_version, --version)."""
__version__ = "0.1.0"

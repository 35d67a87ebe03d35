"""Build helpers of the documentation site (MkDocs): not part of the installed kit."""

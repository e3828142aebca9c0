"""One function per paper table or figure, each returning a pandas DataFrame for a notebook."""

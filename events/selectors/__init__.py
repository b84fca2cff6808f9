"""Read-side queries shared by the API, GUI, collector and report."""

"""Root of the test run: with pytest's default import mode, this file's folder goes first on
sys.path, so the tests import the package of the checkout they belong to (not another editable
install of it)."""

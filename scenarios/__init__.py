"""The scenarios shipped with orbatt (TOML files beside this module); see ``orbatt scenarios``."""

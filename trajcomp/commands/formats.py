"""``trajcomp formats``: list the robot program formats, built-in and plugins."""

from trajcomp.commands._args import command_parser


def add_parser(sub):
    parser = command_parser(
        sub, "formats",
        "List the program formats trajcomp reads and writes: their file extensions, the maker whose controllers "
        "run the language, the fields re-timing writes (none: the language's programs are compensated, not "
        "re-timed), whether its targets declare arm configuration data, and where the format comes from "
        "(built-in, or a plugin of the 'trajcomp.formats' entry-point group).",
        "trajcomp formats",
    )
    parser.set_defaults(run=run)


def run(args):
    from trajcomp import formats  # the registry, with its plugins: what the run lists, not what its --help needs
    from trajcomp.formats.capabilities import ConfigurationData, SpeedFields, Vendor

    rows = [("name", "extensions", "maker", "re-timing writes", "configuration", "source")]
    for fmt in formats.formats():
        speeds, maker = fmt.capability(SpeedFields), fmt.capability(Vendor)
        timing = (speeds.names or "its speed fields") if speeds else "-"
        rows.append((fmt.name, " ".join(fmt.extensions), maker.name if maker else "-", timing,
                     "yes" if fmt.capability(ConfigurationData) else "-", fmt.source))
    rows += [(name, "", "", "", "", f"plugin failed to import: {reason}")
             for name, reason in formats.plugin_failures().items()]
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]) - 1)]
    for row in rows:
        print("  ".join(cell.ljust(width) for cell, width in zip(row, widths)) + "  " + row[-1])
    return 0

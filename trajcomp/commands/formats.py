"""``trajcomp formats``: list the robot program formats, built-in and plugins."""

from trajcomp.commands._args import command_parser


def add_parser(sub):
    parser = command_parser(
        sub, "formats",
        "List the program formats trajcomp reads and writes, their file extensions and where they "
        "come from (built-in, or a plugin of the 'trajcomp.formats' entry-point group).",
        "trajcomp formats",
    )
    parser.set_defaults(run=run)


def run(args):
    from trajcomp import formats  # the registry, with its plugins: what the run lists, not what its --help needs

    for fmt in formats.formats():
        print(f"{fmt.name:10s} {' '.join(fmt.extensions):28s} {fmt.source}")
    for name, reason in formats.plugin_failures().items():
        print(f"{name:10s} {'':28s} plugin failed to import: {reason}")
    return 0

"""Robot programs in memory, whatever their language.

`program` (a program: its source, motions and targets), `items` (one
dataclass per thing a program states), `tables` (motions and targets as
arrays), `frames` (tools and user frames by name) and `configuration`
(each language's arm configuration data). The languages themselves read
and write these in `trajcomp.formats`.
"""

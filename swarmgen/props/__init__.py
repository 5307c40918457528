"""The property language of `swarmgen verify`: temporal properties over member states, counts,
data and events (`tree`), their parser (`parse`) and their type-check against the model
(`check`, a check family of `validate`). docs/verify.md, "User properties"."""

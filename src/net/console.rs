//! The server's console: what its operator types (or a service's standard input sends), one command a line, and
//! the list of banned players it keeps beside the save. Parsing and the ban list are plain data here; the server
//! (`server::run_console_command`) carries the commands out.

use serde::{Deserialize, Serialize};
use std::net::IpAddr;
use std::path::{Path, PathBuf};

/// One line of the console, understood.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ConsoleCommand {
    /// Who is playing, where, from which address.
    List,
    /// Disconnects the player of this name (they may join again).
    Kick(String),
    /// Disconnects the player and refuses their name and address from now on (kept in the ban file).
    Ban(String),
    /// Takes a name (and the addresses banned with it) off the ban list.
    Unban(String),
    /// A line every player sees.
    Say(String),
    Save,
    Quit,
    Help,
    Nothing,
}

/// The console's commands, as `help` prints them.
pub const HELP: &str = "commands: list, kick NAME, ban NAME, unban NAME, say TEXT, save, quit";

/// Reads one console line: a command word and the rest of the line as its argument. `Err` says what is wrong.
pub fn parse_command(line: &str) -> Result<ConsoleCommand, String> {
    let line = line.trim();
    let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
    let rest = rest.trim();
    let needs = |what: &str| -> Result<String, String> {
        if rest.is_empty() { Err(format!("{word} needs {what} ({HELP})")) } else { Ok(rest.to_string()) }
    };
    Ok(match word.to_ascii_lowercase().as_str() {
        "" => ConsoleCommand::Nothing,
        "list" | "who" => ConsoleCommand::List,
        "kick" => ConsoleCommand::Kick(needs("a player's name")?),
        "ban" => ConsoleCommand::Ban(needs("a player's name")?),
        "unban" | "pardon" => ConsoleCommand::Unban(needs("a name")?),
        "say" => ConsoleCommand::Say(needs("a message")?),
        "save" => ConsoleCommand::Save,
        "quit" | "stop" | "exit" => ConsoleCommand::Quit,
        "help" | "?" => ConsoleCommand::Help,
        other => return Err(format!("unknown command '{other}' ({HELP})")),
    })
}

/// Whether two player names are the same player's: names compare without regard to case.
pub fn same_name(a: &str, b: &str) -> bool {
    a.to_lowercase() == b.to_lowercase()
}

/// A banned player: the name, and the addresses they played from when banned.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ban {
    pub name: String,
    #[serde(default)]
    pub addresses: Vec<IpAddr>,
}

/// The ban file: RON, written atomically beside the save (`<save>.bans.ron`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BanList {
    pub bans: Vec<Ban>,
}

/// Bans in one file hold at most this many entries: a larger file is refused as hostile.
const MAX_BANS: usize = 100_000;

impl BanList {
    /// Where the bans of the world saved at `save` are kept.
    pub fn path_beside(save: &Path) -> PathBuf {
        let mut name = save.file_name().map(|n| n.to_os_string()).unwrap_or_default();
        name.push(".bans.ron");
        save.with_file_name(name)
    }

    /// The list at `path`; empty when there is no file, an error naming the file when it cannot be read.
    pub fn load(path: &Path) -> Result<BanList, String> {
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(BanList::default()),
            Err(e) => return Err(format!("cannot read the ban list {}: {e}", path.display())),
        };
        let list: BanList = ron::from_str(&text).map_err(|e| {
            format!(
                "the ban list {} is not a ban list: {}",
                path.display(),
                crate::world::format::one_line(&e.to_string())
            )
        })?;
        if list.bans.len() > MAX_BANS {
            return Err(format!("the ban list {} holds more than {MAX_BANS} bans", path.display()));
        }
        Ok(list)
    }

    pub fn save(&self, path: &Path) -> Result<(), String> {
        let text = ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::default())
            .map_err(|e| format!("cannot write the ban list: {e}"))?;
        crate::world::format::write_atomically(path, text.as_bytes())
            .map_err(|e| format!("cannot write the ban list {}: {e}", path.display()))
    }

    /// Whether a player of this name, or from this address, is banned.
    pub fn refuses(&self, name: Option<&str>, address: Option<IpAddr>) -> bool {
        self.bans.iter().any(|ban| {
            name.is_some_and(|n| same_name(&ban.name, n)) || address.is_some_and(|a| ban.addresses.contains(&a))
        })
    }

    /// Bans `name` (and `address`, when known); an existing ban of the name gains the address.
    pub fn add(&mut self, name: &str, address: Option<IpAddr>) {
        let ban = match self.bans.iter_mut().position(|b| same_name(&b.name, name)) {
            Some(i) => &mut self.bans[i],
            None => {
                self.bans.push(Ban { name: name.to_string(), addresses: Vec::new() });
                self.bans.last_mut().expect("just pushed")
            }
        };
        if let Some(address) = address.filter(|a| !ban.addresses.contains(a)) {
            ban.addresses.push(address);
        }
    }

    /// Lifts the ban of `name`; whether there was one.
    pub fn remove(&mut self, name: &str) -> bool {
        let before = self.bans.len();
        self.bans.retain(|b| !same_name(&b.name, name));
        self.bans.len() != before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_become_commands() {
        assert_eq!(parse_command("  list "), Ok(ConsoleCommand::List));
        assert_eq!(parse_command("kick  Ada Lovelace"), Ok(ConsoleCommand::Kick("Ada Lovelace".into())));
        assert_eq!(parse_command("BAN grief"), Ok(ConsoleCommand::Ban("grief".into())));
        assert_eq!(parse_command("say  dinner at   six"), Ok(ConsoleCommand::Say("dinner at   six".into())));
        assert_eq!(parse_command("stop"), Ok(ConsoleCommand::Quit));
        assert_eq!(parse_command(""), Ok(ConsoleCommand::Nothing));
        assert!(parse_command("kick").unwrap_err().contains("kick needs a player's name"));
        assert!(parse_command("op ada").unwrap_err().contains("unknown command 'op'"));
    }

    #[test]
    fn a_ban_holds_the_name_and_the_address_and_survives_a_restart() {
        let dir = std::env::temp_dir().join(format!("glowbrick-bans-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = BanList::path_beside(&dir.join("world.ron"));
        assert_eq!(path.file_name().unwrap(), "world.ron.bans.ron");
        assert_eq!(BanList::load(&path), Ok(BanList::default()), "no file: nobody is banned");
        let home: IpAddr = "10.0.0.7".parse().unwrap();
        let mut bans = BanList::default();
        bans.add("Grief", Some(home));
        bans.add("grief", Some(home));
        assert_eq!(bans.bans.len(), 1);
        bans.save(&path).unwrap();
        let loaded = BanList::load(&path).unwrap();
        assert!(loaded.refuses(Some("GRIEF"), None), "names compare without case");
        assert!(loaded.refuses(Some("a new name"), Some(home)), "the address is banned too");
        assert!(!loaded.refuses(Some("ada"), Some("10.0.0.8".parse().unwrap())));
        let mut lifted = loaded.clone();
        assert!(lifted.remove("grief") && !lifted.refuses(Some("grief"), Some(home)));
        std::fs::write(&path, "(bans: [(name: 3)])").unwrap();
        let error = BanList::load(&path).unwrap_err();
        assert!(error.contains("world.ron.bans.ron is not a ban list") && !error.contains('\n'), "{error}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}

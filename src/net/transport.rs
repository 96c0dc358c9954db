//! UDP sockets through renet and netcode: a server listening on a port, a client dialing it. With a shared secret
//! both sides derive netcode's 32-byte key from it (Argon2id) and the client makes its own connect token, so only clients
//! that know the secret get in (and their packets are encrypted); without one, netcode's unsecure mode lets
//! anyone connect, and the server says so.

use bevy::prelude::*;
use bevy_replicon::prelude::RepliconChannels;
use bevy_replicon_renet::netcode::{
    ClientAuthentication, ConnectToken, NetcodeClientTransport, NetcodeServerTransport, ServerAuthentication,
    ServerConfig,
};
use bevy_replicon_renet::renet::ConnectionConfig;
use bevy_replicon_renet::{RenetChannelsExt, RenetClient, RenetServer};
use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::time::{Duration, SystemTime};

/// Netcode's protocol id: clients of another protocol version are turned away by the transport itself.
pub const PROTOCOL_ID: u64 = 0x676c_6f77_0000_0001;
/// The port `serve` listens on when none is given.
pub const DEFAULT_PORT: u16 = 47_800;
/// A client that sends nothing for this long is dropped (and a client drops a silent server).
const TIMEOUT_SECONDS: i32 = 10;

/// The salt of every glowbrick secret. Not one per server: the client builds its own connect token from the key,
/// so a salt of the server's own would have to reach it before any encrypted packet, and netcode has no place for
/// that; a salt of our own still keeps tables made for other programs' hashes useless here.
const SECRET_SALT: &[u8] = b"glowbrick connect secret v1";
/// Argon2id's cost (RFC 9106's second recommended option, memory 64 MiB, three passes, one lane): each guess at a
/// secret costs an attacker who captured a token this much memory and time (docs/bench/net/secret.md).
pub const SECRET_MEMORY_KIB: u32 = 64 * 1024;
pub const SECRET_PASSES: u32 = 3;

/// The 32-byte key both sides derive from a shared secret: Argon2id, memory-hard, so a captured connect token
/// lets no one test guesses at the secret quickly offline. Both sides derive it once (listen, dial).
pub fn secret_key(secret: &str) -> [u8; 32] {
    let params = argon2::Params::new(SECRET_MEMORY_KIB, SECRET_PASSES, 1, Some(32)).expect("valid Argon2 parameters");
    let argon = argon2::Argon2::new(argon2::Algorithm::Argon2id, argon2::Version::V0x13, params);
    let mut key = [0u8; 32];
    argon.hash_password_into(secret.as_bytes(), SECRET_SALT, &mut key).expect("a 32-byte key from any secret");
    key
}

fn connection_config(channels: &RepliconChannels) -> ConnectionConfig {
    ConnectionConfig {
        server_channels_config: channels.server_configs(),
        client_channels_config: channels.client_configs(),
        ..default()
    }
}

fn now() -> Duration {
    SystemTime::now().duration_since(SystemTime::UNIX_EPOCH).unwrap_or_default()
}

/// Where a secure client's token also says the server is: every server lists it, so a token made for whatever
/// address the client dialed passes netcode's host check (the key is what authenticates).
fn any_host(port: u16) -> SocketAddr {
    SocketAddr::new(Ipv4Addr::UNSPECIFIED.into(), port)
}

/// Opens the server's socket on `bind` (port 0 picks a free one) and inserts renet's server into an app that has
/// the networking plugins; returns the address it listens on.
pub fn listen(app: &mut App, bind: SocketAddr, secret: Option<&str>, max_clients: usize) -> Result<SocketAddr, String> {
    let (server, transport, local) =
        server_transport(app.world().resource::<RepliconChannels>(), bind, secret, max_clients)?;
    app.insert_resource(server).insert_resource(transport);
    Ok(local)
}

/// renet's server and its netcode transport on a socket bound to `bind`, and the address it listens on.
pub fn server_transport(
    channels: &RepliconChannels,
    bind: SocketAddr,
    secret: Option<&str>,
    max_clients: usize,
) -> Result<(RenetServer, NetcodeServerTransport, SocketAddr), String> {
    let socket = UdpSocket::bind(bind).map_err(|e| format!("cannot listen on {bind}: {e}"))?;
    let local = socket.local_addr().map_err(|e| format!("cannot listen on {bind}: {e}"))?;
    let authentication = match secret {
        Some(secret) => ServerAuthentication::Secure { private_key: secret_key(secret) },
        None => ServerAuthentication::Unsecure,
    };
    let config = ServerConfig {
        current_time: now(),
        max_clients,
        protocol_id: PROTOCOL_ID,
        public_addresses: vec![local, any_host(local.port())],
        authentication,
    };
    let transport = NetcodeServerTransport::new(config, socket).map_err(|e| format!("cannot start the server: {e}"))?;
    Ok((RenetServer::new(connection_config(channels)), transport, local))
}

/// Opens a client socket to `server` and inserts renet's client into an app that has the networking plugins;
/// `client_id` must be unique on the server.
pub fn dial(app: &mut App, server: SocketAddr, secret: Option<&str>, client_id: u64) -> Result<(), String> {
    let (client, transport) = client_transport(app.world().resource::<RepliconChannels>(), server, secret, client_id)?;
    app.insert_resource(client).insert_resource(transport);
    Ok(())
}

/// renet's client and its netcode transport, dialing `server`.
pub fn client_transport(
    channels: &RepliconChannels,
    server: SocketAddr,
    secret: Option<&str>,
    client_id: u64,
) -> Result<(RenetClient, NetcodeClientTransport), String> {
    let bind = SocketAddr::new(
        if server.is_ipv4() { Ipv4Addr::UNSPECIFIED.into() } else { std::net::Ipv6Addr::UNSPECIFIED.into() },
        0,
    );
    let socket = UdpSocket::bind(bind).map_err(|e| format!("cannot open a socket: {e}"))?;
    let authentication = match secret {
        Some(secret) => {
            let token = ConnectToken::generate(
                now(),
                PROTOCOL_ID,
                300,
                client_id,
                TIMEOUT_SECONDS,
                vec![server, any_host(server.port())],
                None,
                &secret_key(secret),
            )
            .map_err(|e| format!("cannot make a connect token: {e}"))?;
            ClientAuthentication::Secure { connect_token: token }
        }
        None => {
            ClientAuthentication::Unsecure { protocol_id: PROTOCOL_ID, client_id, server_addr: server, user_data: None }
        }
    };
    let transport = NetcodeClientTransport::new(now(), authentication, socket)
        .map_err(|e| format!("cannot connect to {server}: {e}"))?;
    Ok((RenetClient::new(connection_config(channels)), transport))
}

/// A client id unlikely to collide with another client's: the clock's nanoseconds mixed with the process id.
pub fn fresh_client_id() -> u64 {
    let mut h = now().as_nanos() as u64 ^ ((std::process::id() as u64) << 32);
    h = (h ^ (h >> 33)).wrapping_mul(0xff51_afd7_ed55_8ccd);
    h ^ (h >> 33)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn secrets_make_distinct_stable_keys() {
        assert_eq!(secret_key("lamp"), secret_key("lamp"));
        assert_ne!(secret_key("lamp"), secret_key("lamp "));
        assert_ne!(secret_key(""), [0u8; 32], "an empty secret still makes a key");
        // Argon2id's reference implementation (the C library, through Python's argon2-cffi) with the same salt
        // and costs gives this key for "lamp".
        let hex: String = secret_key("lamp").iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(hex, "668f30459e69b515ce67802a9b3235190c1f342155993e840f46d93be9ff7bd4");
    }
}

//! UDP sockets through renet and netcode: a server listening on a port, a client dialing it. With a shared secret
//! both sides derive netcode's 32-byte key from it and the client makes its own connect token, so only clients
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

/// The 32-byte key both sides derive from a shared secret (four FNV-1a passes with different seeds; the secret's
/// own strength is what protects the server).
pub fn secret_key(secret: &str) -> [u8; 32] {
    let mut key = [0u8; 32];
    for (lane, out) in key.chunks_mut(8).enumerate() {
        let mut h = 0xcbf2_9ce4_8422_2325_u64 ^ (lane as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        for _ in 0..1024 {
            for &b in secret.as_bytes() {
                h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
            }
            h = (h ^ (h >> 29)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        }
        out.copy_from_slice(&h.to_le_bytes());
    }
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
        let key = secret_key("");
        assert!(key.chunks(8).collect::<std::collections::HashSet<_>>().len() == 4, "the four lanes differ");
    }
}
